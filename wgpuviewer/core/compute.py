"""Compute kernels: compose, compile (errors located at file:line), check limits, bind, dispatch, read back."""

from __future__ import annotations

import hashlib

from .wgsl import Module


def source_hash(module: Module) -> str:
    """sha256 of a composed module's code: what the GPU compiles, so any edit of a file it includes changes it."""
    return hashlib.sha256(module.code.encode()).hexdigest()
