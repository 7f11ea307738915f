"""Errors. ``UserError``: bad input a user can fix (file, TOML, name, value, a missing system piece); the CLIs
print it as one line on stderr and exit with code 2. ``InputError``: a library function called with arguments
it cannot use (shape, range, NaN); a ``ValueError``, which the CLIs also report as one line, exit code 2.
``ApiError``: a UserError met inside the Python API (a scene file, a material's textures, no adapter), raised
again as both, so that the API raises ValueErrors only, as it documents, and the CLIs still report it as theirs.

Imports nothing.
"""


class UserError(Exception):
    """Bad input (file, TOML, name, value) or a missing system piece, with the fix in the message."""

    exit_code = 2


class FileError(UserError):
    """A problem with one input file: ``path`` and ``reason`` (what is wrong and the fix) kept apart, so a caller
    that knows where the file was named (a scene key) can say so: ``scene.toml: materials.m.height = 'x.png': ...``."""

    def __init__(self, path, reason: str):
        super().__init__(f"{path}: {reason}")
        self.path = path
        self.reason = reason


class NoAdapterError(UserError):
    """No wgpu adapter for the requested backend."""


class InputError(ValueError):
    """A library function got arguments it cannot use; the message names the argument and what is expected."""

    exit_code = 2


class ApiError(InputError, UserError):
    """A UserError met inside the Python API (``wgpuviewer.api``), with its message: a ValueError (an InputError)
    for API callers, still a UserError for the CLIs that call the API. The original is its ``__cause__``."""
