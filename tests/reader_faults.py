"""Corrupted engine outputs for the reader fuzz suite (issue 19).

The fixtures in tests/fixtures/engine_outputs/<engine>/ are the raw outputs of real YADE and
LIGGGHTS runs of :func:`fixture_scene` (the C&S nine-disc test, undamped, 100 steps, records every
10 steps, snapshots at 40 and 100, a disc pair and a disc-wall pair tracked), written by
:func:`regenerate` (``python benchmarks/fuzz_readers.py --regenerate``; needs both engines).

:func:`corrupt` makes one corrupted copy of one output file: truncated at a random byte, its lines
reordered (a random swap, a block moved, all shuffled), random bytes overwritten or inserted, a line
deleted or duplicated, a number replaced (NaN, inf, a huge or negative value, a word), the whole file
random bytes or empty, or (JSON) a value of the structure replaced by another type.  The reader must
either refuse the result with :class:`~demflow.engines.EngineOutputError` or, when the corruption
left a well-formed output (a changed digit, lines of one block reordered), return tables; any other
exception is a failure.
"""
from __future__ import annotations

import dataclasses
import hashlib
import json
import random
import re
import shutil
from pathlib import Path

FIXTURES = Path(__file__).resolve().parent / "fixtures" / "engine_outputs"
FILES = {"liggghts": ("log.liggghts", "walls.txt", "contacts.txt", "wallcontacts.txt", "particles.txt"),
         "yade": ("yade_out.json",)}


def fixture_scene():
    from demflow.cases.cs_nine_disc import NineDisc
    from demflow.cases.cs_nine_disc_engines import engine_scene

    sc = engine_scene("undamped", NineDisc().merged())
    sc.name = "reader-fixture"
    sc.n_steps = 100
    sc.outputs = dataclasses.replace(sc.outputs, every=10, snapshots=(40, 100), track_pairs=((4, 5), (0, "wall:bottom")))
    return sc


def regenerate(dest: Path = FIXTURES) -> None:
    """Run YADE and LIGGGHTS on :func:`fixture_scene` and keep their raw outputs as the fixtures."""
    import tempfile

    from demflow.engines import LiggghtsEngine, YadeEngine

    for engine in (LiggghtsEngine(), YadeEngine()):
        with tempfile.TemporaryDirectory() as tmp:
            engine.run(fixture_scene(), Path(tmp), timeout=600)
            out = dest / engine.name
            out.mkdir(parents=True, exist_ok=True)
            for name in FILES[engine.name]:
                shutil.copy2(Path(tmp) / name, out / name)


NUMBER = re.compile(rb"-?\d+(\.\d+)?([eE][-+]?\d+)?")
REPLACEMENTS = [b"nan", b"NaN", b"inf", b"-inf", b"1e999", b"-1", b"-7", b"0", b"99999999999", b"1.5", b"x",
                b"", b"1e308", b"-0", b"3.0e", b"null", b"true", b'"s"', b"[]", b"{}"]
JSON_VALUES = [None, True, "x", -1, 1.5, 10 ** 30, float("nan"), float("inf"), [], {}, [[1.0]], [None], ["a", 1],
               [1.0] * 7, 0]


def _lines(data: bytes) -> list:
    return data.split(b"\n")


def corrupt(data: bytes, rng: random.Random, *, is_json: bool = False) -> tuple[str, bytes]:
    """One corruption of ``data`` drawn by ``rng``: (kind, corrupted bytes)."""
    kinds = ["truncate", "swap-lines", "move-block", "shuffle-lines", "overwrite-bytes", "insert-bytes",
             "delete-line", "duplicate-line", "replace-number", "random-file", "empty"]
    if is_json:
        kinds += ["json-value"] * 4
    kind = rng.choice(kinds)
    n = len(data)
    if kind == "truncate":
        return kind, data[:rng.randrange(n)] if n else data
    if kind == "random-file":
        return kind, bytes(rng.randrange(256) for _ in range(rng.choice([1, 10, 100, 1000, 5000])))
    if kind == "empty":
        return kind, b""
    if kind == "overwrite-bytes":
        b = bytearray(data)
        for _ in range(rng.choice([1, 2, 5, 20])):
            if b:
                b[rng.randrange(len(b))] = rng.randrange(256)
        return kind, bytes(b)
    if kind == "insert-bytes":
        k = rng.randrange(n + 1)
        return kind, data[:k] + bytes(rng.randrange(256) for _ in range(rng.choice([1, 3, 16]))) + data[k:]
    if kind == "replace-number":
        nums = list(NUMBER.finditer(data))
        if not nums:
            return kind, data + b"x"
        m = rng.choice(nums)
        return kind, data[:m.start()] + rng.choice(REPLACEMENTS) + data[m.end():]
    if kind == "json-value":
        return kind, _json_value(data, rng)
    lines = _lines(data)
    if len(lines) < 2:
        return kind, data[::-1]
    if kind == "swap-lines":
        i, j = rng.randrange(len(lines)), rng.randrange(len(lines))
        lines[i], lines[j] = lines[j], lines[i]
    elif kind == "move-block":
        i = rng.randrange(len(lines))
        j = min(len(lines), i + rng.choice([1, 5, 20, 100]))
        block = lines[i:j]
        del lines[i:j]
        k = rng.randrange(len(lines) + 1)
        lines[k:k] = block
    elif kind == "shuffle-lines":
        rng.shuffle(lines)
    elif kind == "delete-line":
        del lines[rng.randrange(len(lines))]
    elif kind == "duplicate-line":
        i = rng.randrange(len(lines))
        lines.insert(i, lines[i])
    return kind, b"\n".join(lines)


def _json_value(data: bytes, rng: random.Random) -> bytes:
    """Replace one value somewhere in the JSON structure (a key's value or a list entry) by another type,
    or delete a key."""
    try:
        obj = json.loads(data)
    except ValueError:
        return data[: len(data) // 2]
    nodes = []

    def walk(o, depth):
        if isinstance(o, dict):
            for k in o:
                nodes.append((o, k))
                walk(o[k], depth + 1)
        elif isinstance(o, list):
            for k in range(len(o)):
                if rng.random() < 0.2 or len(o) < 4:
                    nodes.append((o, k))
                    walk(o[k], depth + 1)

    walk(obj, 0)
    parent, key = rng.choice(nodes)
    if isinstance(parent, dict) and rng.random() < 0.25:
        del parent[key]
    else:
        parent[key] = rng.choice(JSON_VALUES)
    return json.dumps(obj).encode()


def corrupted_copy(src: Path, names, dest: Path, rng: random.Random) -> tuple[str, str]:
    """Copy the files ``names`` of ``src`` into ``dest`` with one of them corrupted; returns (file, kind)."""
    dest.mkdir(parents=True, exist_ok=True)
    for name in names:
        shutil.copyfile(src / name, dest / name)
    name = rng.choice(names)
    kind, data = corrupt((src / name).read_bytes(), rng, is_json=name.endswith(".json"))
    (dest / name).write_bytes(data)
    return name, kind


def corrupted_dir(engine: str, dest: Path, rng: random.Random) -> tuple[str, str]:
    """Copy the engine's fixture outputs into ``dest`` with one file corrupted; returns (file, kind)."""
    return corrupted_copy(FIXTURES / engine, FILES[engine], dest, rng)


def fingerprint(root: Path) -> str:
    """sha256 over every file's path and content under ``root``."""
    h = hashlib.sha256()
    for p in sorted(root.rglob("*")):
        if p.is_file():
            h.update(str(p.relative_to(root)).encode())
            h.update(p.read_bytes())
    return h.hexdigest()


def replay_engine(engine_name: str, src: Path):
    """An engine of the given kind whose 'run' copies the files of ``src`` (the deck is written as usual)."""
    from demflow.engines import LiggghtsEngine, YadeEngine

    base = {"liggghts": LiggghtsEngine, "yade": YadeEngine}[engine_name]

    class Replay(base):
        def path(self):
            return shutil.which("cp")

        def command(self, deckdir):
            return ["cp", "-r", f"{src}/.", "."]

        def version(self):
            return "replay"

    return Replay()


def read(engine: str, sim, outdir: Path):
    from demflow.engines import get_engine

    return get_engine(engine).read(sim.scene, sim, outdir)
