"""Atomic file writes: every file demflow writes (tables, checkpoints, reports, engine decks, VTK collections)
appears whole under its name or not at all.

The content goes to a temporary file beside the target (same directory, so the rename stays on one file system),
which is then renamed over it (``os.replace``, atomic on POSIX and Windows).  A write that fails removes its
temporary file and leaves the previous file as it was.  The file gets the permissions an ordinary ``open()``
would give it (0666 less the process's umask): ``tempfile.mkstemp`` creates files readable by their owner only,
which made reports and checkpoints unreadable to the other users of a shared machine or a web server.
"""
from __future__ import annotations

import json
import os
import tempfile
import threading
from pathlib import Path
from typing import Callable


_UMASK_LOCK = threading.Lock()


def _umask() -> int:
    """The process's umask now (it may change after import: each write reads it).  Linux states it in
    /proc/self/status, read without touching it; elsewhere it is set and restored under a lock (the only
    portable way to read it; another thread creating a file in between would see 0o022)."""
    try:
        with open("/proc/self/status", encoding="ascii", errors="replace") as fh:
            for line in fh:
                if line.startswith("Umask:"):
                    return int(line.split()[1], 8)
    except (OSError, ValueError, IndexError):
        pass
    with _UMASK_LOCK:
        mask = os.umask(0o022)
        os.umask(mask)
    return mask


def write_atomic(path, write: Callable[[str], object]) -> Path:
    """Call ``write(tmp)`` with the name of a temporary file beside ``path`` (created empty; ``write`` may
    replace it), then rename it to ``path``.  The parent directories are created.  Returns ``path``."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=".tmp")
    os.close(fd)
    try:
        write(tmp)
        os.chmod(tmp, 0o666 & ~_umask())
        os.replace(tmp, path)
    finally:
        if os.path.exists(tmp):
            os.remove(tmp)
    return path


def write_text_atomic(path, text: str) -> Path:
    """``text`` (UTF-8) to ``path``, atomically."""
    return write_atomic(path, lambda tmp: Path(tmp).write_text(text, encoding="utf-8"))


def write_bytes_atomic(path, data: bytes) -> Path:
    """``data`` to ``path``, atomically."""
    return write_atomic(path, lambda tmp: Path(tmp).write_bytes(data))


def write_json_atomic(path, obj, **dump_kw) -> Path:
    """``json.dumps(obj, **dump_kw)`` to ``path``, atomically (serialised before the file is touched)."""
    return write_text_atomic(path, json.dumps(obj, **dump_kw))
