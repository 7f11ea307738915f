"""Errors a user can cause. The CLIs print them as one line on stderr and exit with code 2."""


class UserError(Exception):
    """Bad input (file, TOML, name, value) or a missing system piece, with the fix in the message."""

    exit_code = 2


class NoAdapterError(UserError):
    """No wgpu adapter for the requested backend."""
