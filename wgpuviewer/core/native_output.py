"""What native decoders print, taken into our one line: libpng, libjpeg and OpenEXR print their complaints on the
process's file descriptor 2 themselves (the ``openexr`` module also through Python's stdout). ``native_stderr``
and ``python_stdout`` capture those lines around a decode, so they end up in the reader's one line (the reason of
a decode that failed, or a warning naming the file when the decoder recovered) instead of on the terminal."""

from __future__ import annotations

import contextlib
import os
import sys
import tempfile
import threading

_NATIVE_STDERR_LOCK = threading.Lock()


def _writes_to_fd2(stream) -> bool:
    try:
        return stream.fileno() == 2
    except (AttributeError, OSError, ValueError):  # pytest's capture, a closed or replaced stream
        return False


class _HeldStderr:
    """Stands in for ``sys.stderr`` while a decode holds file descriptor 2: other threads' writes wait for the
    decode to end and then go to the stream that was there, so none is taken for the decoder's. Whoever keeps a
    reference past the decode writes straight through."""

    def __init__(self, stream, released: threading.Event):
        self._stream, self._released, self._owner = stream, released, threading.get_ident()

    def write(self, text):
        if threading.get_ident() != self._owner:
            self._released.wait()
        return self._stream.write(text)

    def __getattr__(self, name):  # flush, fileno, isatty, encoding, ...
        return getattr(self._stream, name)


@contextlib.contextmanager
def native_stderr(messages: list[str]):
    """Appends to ``messages`` the lines native code prints on file descriptor 2 during the block, instead of
    letting them reach the terminal ahead of our own line. One block at a time holds the descriptor; Python's
    stderr is held meanwhile (``_HeldStderr``), and terminal redraws written to the descriptor (a progress bar:
    lines with CR or escape codes) are passed on."""
    with _NATIVE_STDERR_LOCK, tempfile.TemporaryFile() as sink:
        python_stderr = sys.stderr
        with contextlib.suppress(Exception):
            python_stderr.flush()
        try:
            saved = os.dup(2)
        except OSError:  # no descriptor 2 (a detached process): nothing to take
            yield
            return
        released = threading.Event()
        held = _HeldStderr(python_stderr, released) if _writes_to_fd2(python_stderr) else None
        if held is not None:
            sys.stderr = held
        os.dup2(sink.fileno(), 2)
        try:
            yield
        finally:
            os.dup2(saved, 2)
            os.close(saved)
            released.set()
            if held is not None and sys.stderr is held:
                sys.stderr = python_stderr
            sink.seek(0)
            lines = sink.read().decode(errors="replace").split("\n")
            for i, line in enumerate(lines):
                if "\r" in line or "\x1b" in line:
                    with contextlib.suppress(Exception):
                        python_stderr.write(line + ("\n" if i < len(lines) - 1 else ""))
                        python_stderr.flush()
                elif line.strip():
                    messages.append(line.strip())


class _CapturedStdout:
    """Stands in for ``sys.stdout`` while the ``openexr`` module decodes: what the decoding thread prints (the
    module's warnings) is kept; other threads write to the stream that was there."""

    def __init__(self, stream):
        self._stream, self._owner, self.text = stream, threading.get_ident(), []

    def write(self, text):
        if threading.get_ident() != self._owner:
            return self._stream.write(text)
        self.text.append(text)
        return len(text)

    def __getattr__(self, name):  # flush, fileno, isatty, encoding, ...
        return getattr(self._stream, name)


@contextlib.contextmanager
def python_stdout(messages: list[str]):
    """Appends to ``messages`` the lines this thread prints through Python's stdout during the block."""
    captured = _CapturedStdout(sys.stdout)
    sys.stdout = captured
    try:
        yield
    finally:
        if sys.stdout is captured:
            sys.stdout = captured._stream
        messages.extend(line.strip() for line in "".join(captured.text).splitlines() if line.strip())
