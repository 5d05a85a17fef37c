"""Is a checkpoint this scene's?  A digest of what a scene fixes and a run does not change.

A checkpoint (``save_checkpoint``) holds the dynamic state of a run: positions, velocities, contact history.  It
continues a run only in a simulation built from the same scene: the same particles (radii, masses, inertia,
materials), time step, gravity, walls, box and contact-law parameters.  :func:`scene_digest` condenses each of
these parts to a short hash (sha256 of the array bytes, their dtype and shape), written into the checkpoint's meta;
:func:`check_same_scene` compares them at load and names the parts that differ.  A checkpoint written before the
digest existed (no ``"static"`` in its meta) is loaded as before, on the scene's name and counts alone.
"""
from __future__ import annotations

import hashlib
import os
import tempfile
from pathlib import Path

import numpy as np


def _feed(h, name: str, value) -> None:
    """Feed ``value`` into the hash ``h``: a named tuple field by field, a tuple or list item by item, else as one
    array (its dtype, shape and bytes)."""
    if hasattr(value, "_asdict"):
        for k, v in value._asdict().items():
            _feed(h, f"{name}.{k}", v)
    elif isinstance(value, (tuple, list)):
        for k, v in enumerate(value):
            _feed(h, f"{name}[{k}]", v)
    else:
        a = np.ascontiguousarray(np.asarray(value))
        h.update(f"{name}:{a.dtype.str}:{a.shape}".encode())
        h.update(a.view(np.uint8).tobytes() if a.size else b"")


def _digest(value) -> str:
    h = hashlib.sha256()
    _feed(h, "", value)
    return h.hexdigest()[:16]


def scene_digest(parts: dict) -> dict[str, str]:
    """A hash per named part (arrays, numbers or named tuples of arrays such as a law's compiled parameters)."""
    return {name: _digest(v) for name, v in parts.items()}


def check_same_scene(path, meta: dict, now: dict[str, str]) -> None:
    """Raise ValueError when the checkpoint at ``path`` (its ``meta``) was written by a scene whose fixed parts differ
    from this simulation's (``now``, its :func:`scene_digest`); a checkpoint without digests passes."""
    saved = meta.get("static")
    if not saved:
        return
    differ = sorted(k for k in set(saved) | set(now) if saved.get(k) != now.get(k))
    if differ:
        raise ValueError(
            f"checkpoint {path} was written by another scene named {meta.get('scene')!r}: these parts differ from "
            f"this scene's: {'; '.join(differ)}. A checkpoint continues only the scene that wrote it: build that "
            "scene, or run this one from its start")


def write_checkpoint(path, meta: dict, state: dict):
    """Write a checkpoint: ``meta`` (JSON) and the ``state`` arrays by name into the .npz ``path``, atomically
    (:func:`demflow.atomic.write_atomic`); returns the path.  :func:`read_checkpoint` reads it back."""
    import json
    from pathlib import Path

    from .atomic import write_atomic

    def save(tmp):
        with open(tmp, "wb") as fh:
            np.savez(fh, meta=json.dumps(meta), **state)

    return write_atomic(Path(path), save)


def read_checkpoint(path) -> tuple[dict, dict]:
    """(meta, state arrays by name) of the checkpoint at ``path``; a file that is not one (another .npz, a text
    file, a truncated write) is a ValueError saying so, not NumPy's message about pickled data."""
    import json
    import zipfile

    try:
        with np.load(path, allow_pickle=False) as z:
            if "meta" not in z.files:
                raise ValueError("it has no 'meta' entry")
            meta = json.loads(str(z["meta"]))
            state = {k: z[k].copy() for k in z.files if k != "meta"}
    except FileNotFoundError:
        raise
    except (ValueError, OSError, EOFError, zipfile.BadZipFile, json.JSONDecodeError) as e:
        raise ValueError(f"{path} is not a demflow checkpoint (an .npz written by save_checkpoint): {e}") from None
    return meta, state


def last_good_path(scene_name: str, step: int) -> Path:
    """Where a run that blew up saves its last good state: ``$DEMFLOW_BLOWUP_DIR`` (default the system's temporary
    directory) / ``<scene name>-last-good-step<step>.npz``."""
    out = Path(os.environ.get("DEMFLOW_BLOWUP_DIR", tempfile.gettempdir()))
    return out / f"{scene_name}-last-good-step{step}.npz"
