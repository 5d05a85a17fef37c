"""VTK output for ParaView (pyevtk's XML writers: .vtu files and a .pvd time series).

Two files a snapshot:

- ``<prefix>_particles_<step>.vtu``: one point per particle at its centre (2D: z = 0), with point
  data ``id``, ``radius``, the velocity vector ``velocity`` and, in 2D, ``theta`` and ``omega``; in
  3D ``angular_velocity``.  In ParaView, show them with the Glyph filter (sphere glyph, scale array
  ``radius``, scale factor 2: a glyph's size is its diameter).
- ``<prefix>_contacts_<step>.vtu``: one line cell per touching contact, the branch from particle i's
  centre to the contact (disc–disc and sphere–sphere: on to the image of j's centre, so lines stay
  short across periodic boundaries; a wall or plane contact ends on the wall), with cell data
  ``fn`` (normal force, N or N/m in 2D, compression positive), ``fs`` (tangential force magnitude),
  ``overlap`` and ``sliding`` (1 or 0).  Colour and width by ``fn`` for force chains.

``<prefix>.pvd`` lists them by time, so ParaView opens the whole run as one time series.  Every file
is written to a temporary name in the output directory and renamed into place (atomic).
"""
from __future__ import annotations

import os
import tempfile
from pathlib import Path

import numpy as np

from .atomic import write_text_atomic

VTK_LINE = 3  # the VTK cell type of a two-point line


def _atomic(writer, path: Path, *args, **kw) -> Path:
    """Call a pyevtk writer on a temporary name beside ``path`` (it appends ``.vtu``), then rename."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    tmpdir = tempfile.mkdtemp(dir=path.parent, prefix=".vtk-")
    try:
        written = Path(writer(os.path.join(tmpdir, "f"), *args, **kw))
        os.replace(written, path)
    finally:
        for f in Path(tmpdir).iterdir():
            f.unlink()
        os.rmdir(tmpdir)
    return path


def _c(a) -> np.ndarray:
    return np.ascontiguousarray(np.asarray(a, dtype=np.float64))


def write_points(path, xyz: np.ndarray, data: dict) -> Path:
    """Particles as VTK points with point data (scalars: 1-D arrays; vectors: (n, 3) arrays)."""
    from pyevtk.hl import pointsToVTK

    xyz = _c(xyz).reshape(-1, 3)
    out = {}
    for k, v in data.items():
        v = np.asarray(v)
        out[k] = tuple(_c(v[:, a]) for a in range(3)) if v.ndim == 2 else _c(v)
    return _atomic(pointsToVTK, path, _c(xyz[:, 0]), _c(xyz[:, 1]), _c(xyz[:, 2]), data=out)


def write_lines(path, start: np.ndarray, end: np.ndarray, cell_data: dict) -> Path:
    """Contacts as VTK line cells from ``start`` to ``end`` ((m, 3) each) with cell data.  With no contact
    (m = 0) the file is an empty unstructured grid with the same cell-data arrays (:func:`_write_empty_grid`)."""
    from pyevtk.hl import unstructuredGridToVTK

    start, end = _c(start).reshape(-1, 3), _c(end).reshape(-1, 3)
    m = start.shape[0]
    if m == 0:
        return _write_empty_grid(path, list(cell_data))
    pts = np.empty((2 * m, 3))
    pts[0::2], pts[1::2] = start, end
    conn = np.arange(2 * m, dtype=np.int64)
    offsets = 2 * np.arange(1, m + 1, dtype=np.int64)
    types = np.full(m, VTK_LINE, dtype=np.uint8)
    cd = {k: _c(v) for k, v in cell_data.items()}
    return _atomic(unstructuredGridToVTK, path, _c(pts[:, 0]), _c(pts[:, 1]), _c(pts[:, 2]), connectivity=conn,
                   offsets=offsets, cell_types=types, cellData=cd)


def _write_empty_grid(path, cell_arrays: list[str]) -> Path:
    """An unstructured grid with no point and no cell, its cell-data arrays named (a snapshot with no contact:
    pyevtk refuses to write an empty piece, and ParaView reads a time series best when every step has the file
    and its arrays).  Written by hand: VTK's XML format, ASCII, a few lines; atomically."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    arrays = "".join(f'        <DataArray type="Float64" Name="{name}" format="ascii">\n        </DataArray>\n'
                     for name in cell_arrays)
    text = ('<?xml version="1.0"?>\n<VTKFile type="UnstructuredGrid" version="0.1" byte_order="LittleEndian">\n'
            '  <UnstructuredGrid>\n    <Piece NumberOfPoints="0" NumberOfCells="0">\n'
            '      <Points>\n        <DataArray type="Float64" NumberOfComponents="3" format="ascii">\n        </DataArray>\n'
            '      </Points>\n      <Cells>\n'
            '        <DataArray type="Int64" Name="connectivity" format="ascii">\n        </DataArray>\n'
            '        <DataArray type="Int64" Name="offsets" format="ascii">\n        </DataArray>\n'
            '        <DataArray type="UInt8" Name="types" format="ascii">\n        </DataArray>\n'
            f'      </Cells>\n      <CellData>\n{arrays}      </CellData>\n    </Piece>\n  </UnstructuredGrid>\n'
            '</VTKFile>\n')
    return write_text_atomic(path, text)


def write_pvd(path, entries) -> Path:
    """A ParaView collection: ``entries`` = [(time, file name relative to the .pvd), ...]."""
    path = Path(path)
    rows = "\n".join(f'    <DataSet timestep="{float(t)!r}" group="" part="{part}" file="{f}"/>'
                     for t, part, f in entries)
    text = ('<?xml version="1.0"?>\n<VTKFile type="Collection" version="0.1" byte_order="LittleEndian">\n'
            f"  <Collection>\n{rows}\n  </Collection>\n</VTKFile>\n")
    return write_text_atomic(path, text)


def write_results_vtk(results, outdir, prefix: str = "run") -> list[Path]:
    """Every snapshot of a 2D :class:`~demflow.results.Results` (demflow's or an engine's) as VTK:
    particles and contacts per snapshot step, and ``<prefix>.pvd``; returns the files written."""
    outdir = Path(outdir)
    outdir.mkdir(parents=True, exist_ok=True)
    parts, cons = results.particles, results.contacts
    files, entries = [], []
    for step in sorted(set(parts["step"].astype(int))):
        p = parts[parts.step == step].sort_values("id")
        t = float(p["time"].iloc[0]) if len(p) else 0.0
        z = np.zeros(len(p))
        xyz = np.c_[p.x, p.y, z]
        f1 = write_points(outdir / f"{prefix}_particles_{step:09d}.vtu", xyz, {
            "id": p.id.to_numpy(float), "radius": p.radius, "theta": p.theta, "omega": p.omega,
            "velocity": np.c_[p.vx, p.vy, z]})
        c = cons[cons.step == step]
        centre = dict(zip(p.id.astype(int), zip(p.x, p.y)))
        radius = dict(zip(p.id.astype(int), p.radius))
        start = np.array([centre[int(i)] for i in c.i]).reshape(-1, 2)
        contact = np.c_[c.px, c.py]
        branch = contact - start
        length = np.linalg.norm(branch, axis=1)
        far = np.array([radius[int(j)] if j >= 0 else 0.0 for j in c.j])
        scale = np.where(length > 0, (length + far) / np.where(length > 0, length, 1.0), 1.0)
        end = start + branch * scale[:, None]
        zc = np.zeros(len(c))
        f2 = write_lines(outdir / f"{prefix}_contacts_{step:09d}.vtu", np.c_[start, zc], np.c_[end, zc], {
            "fn": c.fn, "fs": np.abs(c.fs), "overlap": c.overlap, "sliding": c.sliding.to_numpy(float)})
        files += [f1, f2]
        entries += [(t, 0, f1.name), (t, 1, f2.name)]
    if files:
        files.append(write_pvd(outdir / f"{prefix}.pvd", entries))
    return files


def write_simulation3d_vtk(sim, outdir, prefix: str = "run") -> list[Path]:
    """The current state of a :class:`~demflow.simulation3d.Simulation3D` as VTK (spheres and touching
    contacts at ``sim.step``); call it after each stage of a run for a series."""
    from .contacts.spheres import closest_point_triangle

    outdir = Path(outdir)
    sp, p = sim.spheres, sim.pairs
    step = int(sim.step)
    f1 = write_points(outdir / f"{prefix}_particles_{step:09d}.vtu", sp.pos, {
        "id": np.arange(sim.n, dtype=float), "radius": sp.r, "velocity": sp.vel, "angular_velocity": sp.angvel})
    on = np.flatnonzero(p.ovl > 0)
    start = sp.pos[p.i[on]]
    end = np.empty_like(start)
    n, npl = sim.n, sim.planes.point.shape[0]
    for q, k in enumerate(on):
        i, j = p.i[k], p.j[k]
        if j < n:
            end[q] = sp.pos[j] + p.shift[k]
        elif j < n + npl:  # a plane: the foot of the centre on it
            nrm = sim.planes.normal[j - n]
            end[q] = sp.pos[i] - np.dot(sp.pos[i] - sim.planes.point[j - n], nrm) * nrm
        else:  # a mesh triangle: its closest point
            x, y, z, _ = closest_point_triangle(sp.pos[i, 0], sp.pos[i, 1], sp.pos[i, 2], sim.tris.v[j - n - npl])
            end[q] = (x, y, z)
    ft = np.linalg.norm(p.ft[on], axis=1) if on.size else np.zeros(0)
    f2 = write_lines(outdir / f"{prefix}_contacts_{step:09d}.vtu", start, end, {
        "fn": p.fn[on], "fs": ft, "overlap": p.ovl[on], "sliding": p.slide[on].astype(float)})
    t = step * sim.dt
    f3 = write_pvd(outdir / f"{prefix}.pvd", [(t, 0, f1.name), (t, 1, f2.name)])
    return [f1, f2, f3]


__all__ = ["write_points", "write_lines", "write_pvd", "write_results_vtk", "write_simulation3d_vtk"]
