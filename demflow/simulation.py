"""A built simulation: structure-of-arrays state plus the compiled calculation cycle.

Created by :func:`demflow.build.build`; never construct it by hand.  ``run`` advances it,
``results`` returns the tables, ``save_checkpoint``/``load_checkpoint`` make long runs
resumable (atomic writes).
"""
from __future__ import annotations

import math
import os
import time
import warnings
from pathlib import Path

import numpy as np

from .checkpoint_scene import check_same_scene, last_good_path, read_checkpoint, scene_digest, write_checkpoint
from .contacts.forces import NO_PAIRS, pair_forces
from .contacts.neighbours import (cell_order, cell_side, internal_layout, outer_list_holds, pairs_cell_search_ordered,
                                  pairs_within, spatial_order, transfer_history)
from .contacts.periodic import pairs_periodic
from .integrate import Q_WIDTH, pack_rows
from .jit import check_thread_count
from .scene import MAX_WHOLE, EnergyBalanceWarning, SceneError, check_whole
from .space import wrap
from .state import (Layout, Loading, Pairs, PeriodicBox, Records, Walls, empty_pairs, new_discs,
                    pair_outputs)
from .stepping import (BLOWUP, MAX_OVERLAP_RATIO, MAX_STEP_RATIO, NONFINITE, REBUILD, elastic_energy_keys,
                       force_sums_keys, run_steps, state_is_finite)
from .tolerances import tol


# A chunk's created energy below this fraction of the energies it moved is round-off (sums of ~1e4 terms).
ENERGY_ROUND_OFF = 1e-9
# The wider pair list the neighbour-list builds of a box without periodic axes filter, in skins (see
# Simulation._pairs_from_outer_list): it holds every pair the cell search would list while the discs moved less than
# (OUTER_SKIN - 1)/2 skins since its build, so it serves several builds (each after the fastest disc moved skin/2).
# A speed knob only: the lists, and so the results, are those of the cell search whatever its value
# (tests/test_properties.py; speed_experiments_session49.md).
OUTER_SKIN = 4.0


class BlowUpError(RuntimeError):
    """The run became unstable; ``path`` holds the last good state."""

    def __init__(self, message: str, path: str | None):
        super().__init__(message)
        self.path = path


# ------------------------------------------------------------------ what a run can store
# Bytes per recorded step: the Records rows (step, wall force and point, tracked fn/fs, energies) held
# twice while a run's chunks are joined, plus the rows of the result tables built from them
# (wall_forces 8 columns per wall, tracked 6 per pair, energy 4).
def record_bytes(nw: int, nt: int) -> int:
    return 2 * 8 * (3 + 5 * nw + 2 * nt) + 64 * nw + 48 * nt + 32


SNAPSHOT_BYTES_PER_DISC = 400  # a particles row (10 columns) and about two contact rows (16 columns)


def memory_limit() -> int:
    """What one run may hold in records and tables [bytes]: half of this machine's physical memory
    (``DEMFLOW_MEMORY_LIMIT`` in bytes overrides it)."""
    env = os.environ.get("DEMFLOW_MEMORY_LIMIT")
    if env:
        return int(float(env))
    try:
        return os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES") // 2
    except (ValueError, OSError, AttributeError):
        return 8 << 30


def recorded_steps(step0: int, n_steps: int, every: int) -> int:
    """How many of the steps step0 .. step0 + n_steps - 1 are recorded (multiples of ``every``)."""
    if every <= 0 or n_steps <= 0:
        return 0
    return (step0 + n_steps - 1) // every - (step0 - 1) // every


def check_run_length(path: str, n_steps: int, scene, n: int, nw: int, nt: int, step0: int = 0) -> None:
    """Refuse up front a run whose records, snapshots and (saturated scenes) fluid records would not fit
    in :func:`memory_limit`, with the numbers; memory grows with what is recorded, not with n_steps."""
    if not 0 <= n_steps <= MAX_WHOLE - step0:
        raise SceneError(f"{path}={n_steps} is out of range; give a whole number of steps from 0 to {MAX_WHOLE - step0}")
    every = int(scene.outputs.every)
    target = step0 + n_steps
    rows = recorded_steps(step0, n_steps, every)
    per = record_bytes(nw, nt)
    need = rows * per
    snaps = sum(1 for s in scene.outputs.snapshots if step0 <= s <= target)
    need += snaps * n * SNAPSHOT_BYTES_PER_DISC
    f = scene.fluid
    if f is not None:
        solves = max(target - max(step0, int(f.start)), 0) // int(f.stride) + 1
        need += (solves // int(f.record_every) + 1) * (n * 128 + 4096)
    limit = memory_limit()
    if need > limit:
        fit = limit // per if per else 0
        hint = (f"record less often (scene.outputs.every >= {max(-(-n_steps // max(fit, 1)), every + 1)}, or 0 for "
                "no records), " if rows else "")
        raise SceneError(
            f"{path}={n_steps}: the run would hold about {need / 2 ** 30:.4g} GiB ({rows:,} recorded steps × {per} "
            f"bytes for {nw} walls and {nt} tracked pairs, {snaps} snapshots of {n} discs"
            f"{', fluid records' if f is not None else ''}), more than the {limit / 2 ** 30:.4g} GiB a run may hold "
            f"(half of this machine's memory; DEMFLOW_MEMORY_LIMIT overrides it); {hint}shorten the run or take "
            "fewer snapshots")


# arrays that make up the dynamic state (what a checkpoint stores), by the structure that holds them
_DISC_STATE = ("x", "y", "th", "vx", "vy", "om")
_WALL_STATE = {"wpx": "px", "wpy": "py", "wex": "ex", "wey": "ey", "wvx": "vx", "wvy": "vy", "wom": "om",
               "wcx": "cx", "wcy": "cy"}
_PAIR_STATE = ("finder", "other", "hist")
_LIST_STATE = ("sx", "sy", "perm", "xref", "yref", "disp_walls")  # the pair list's build (Simulation._set_state)
_STATE = _DISC_STATE + tuple(_WALL_STATE) + _PAIR_STATE
# wall attributes by their historical names (sim.wpx is sim.walls.px)
_WALL_ALIASES = dict(_WALL_STATE, wh1="h1", wh2="h2", wmat="mat", wall_force="force")


def first_nonfinite(arrays: dict) -> str | None:
    """"name[index] = value" of the first non-finite entry of the named arrays, or None.  A sum screens
    each array (NaN and ±inf propagate through it; a sum that overflows only sends it to the exact test)."""
    with np.errstate(over="ignore", invalid="ignore"):
        for name, a in arrays.items():
            if a.size and not np.isfinite(a.sum()):
                bad = np.argwhere(~np.isfinite(a))
                if bad.size:
                    idx = tuple(int(i) for i in bad[0])
                    return f"{name}[{', '.join(map(str, idx))}] = {a[idx]}"
    return None


def walls_and_loading(scene, wall_geo, wall_mat):
    """The :class:`~demflow.state.Walls` and :class:`~demflow.state.Loading` of ``scene.walls``
    (``wall_geo``: per wall (ax, ay, bx, by, px, py, ex, ey) from :func:`demflow.build.wall_geometry`,
    ``wall_mat``: material indices)."""
    nw = len(wall_geo)
    g = np.array(wall_geo, dtype=np.float64).reshape(nw, 8)
    px, py = g[:, 4].copy(), g[:, 5].copy()
    walls = Walls(px=px, py=py, ex=g[:, 6].copy(), ey=g[:, 7].copy(),
                  h1=np.array([w.h1 for w in scene.walls], dtype=np.float64),
                  h2=np.array([w.h2 for w in scene.walls], dtype=np.float64),
                  vx=np.zeros(nw), vy=np.zeros(nw), om=np.zeros(nw), cx=px.copy(), cy=py.copy(),
                  mat=wall_mat, force=np.zeros((nw, 3)))
    K = max([len(w.phases) for w in scene.walls], default=0) or 1
    ld = Loading(phase_start=np.zeros((nw, K), np.int64), phase_end=np.zeros((nw, K), np.int64),
                 phase_vx=np.zeros((nw, K)), phase_vy=np.zeros((nw, K)), phase_om=np.zeros((nw, K)),
                 phase_cx=np.zeros((nw, K)), phase_cy=np.zeros((nw, K)),
                 phase_about_p=np.ones((nw, K), np.int8), servo_on=np.zeros(nw, np.int8),
                 servo_start=np.zeros(nw, np.int64), servo_F=np.zeros(nw), servo_dx=np.zeros(nw),
                 servo_dy=np.zeros(nw), servo_G=np.zeros(nw), servo_vmax=np.zeros(nw))
    for w, wall in enumerate(scene.walls):
        s0 = 0
        for k, ph in enumerate(wall.phases):
            ld.phase_start[w, k] = s0
            ld.phase_end[w, k] = s0 + int(ph.cycles)
            s0 += int(ph.cycles)
            ld.phase_vx[w, k], ld.phase_vy[w, k] = map(float, ph.velocity)
            ld.phase_om[w, k] = float(ph.omega)
            if ph.pivot is not None:
                ld.phase_about_p[w, k] = 0
                ld.phase_cx[w, k], ld.phase_cy[w, k] = map(float, ph.pivot)
        if wall.servo is not None:
            s = wall.servo
            L = float(np.hypot(*s.direction))
            ld.servo_on[w] = 1
            ld.servo_start[w] = s.start
            ld.servo_F[w] = s.force
            ld.servo_dx[w], ld.servo_dy[w] = s.direction[0] / L, s.direction[1] / L
            ld.servo_G[w], ld.servo_vmax[w] = s.gain, s.v_max
    return walls, ld


def _disc_alias(field):
    return property(lambda self: getattr(self.discs, field), doc=f"discs.{field} (disc order)")


def _wall_alias(field):
    return property(lambda self: getattr(self.walls, field), doc=f"walls.{field}")


def _pair_alias(field):
    return property(lambda self: getattr(self.pairs, field), doc=f"pairs.{field} (key order)")


class Simulation:
    """State and stepping of one 2D disc scene (see :mod:`demflow.build`).

    The state lives in a few named structures of arrays (:mod:`demflow.state`): ``discs``
    (disc order), ``walls`` and ``loading``, ``pairs`` (the neighbour list with its history, key
    order), plus the law's compiled parameters ``law_params`` and the ``box``.  ``x``, ``vx``,
    ``wpx``, ``hist``, ... are read-only names for fields of these structures.
    """

    CHUNK = 20000  # steps between last-good-state copies
    _bar = None  # the progress bar of the run in progress (set by run, see demflow.progress)
    # Below this many discs a step is too short to share between threads: on this 2-core
    # machine the nine-disc test ran 65× slower on 2 threads than on 1 (4.06 s vs 0.063 s,
    # 9040 steps); benchmarks/results/crossover.md: 2 threads pay off above ~4000 discs
    # (0.91× at 4000, 1.74× at 10000).
    PARALLEL_MIN_DISCS = 8000

    for _f in ("x", "y", "th", "vx", "vy", "om", "r", "mass", "inertia", "mat", "C", "Cr"):
        locals()[_f] = _disc_alias(_f)
    for _a, _f in _WALL_ALIASES.items():
        locals()[_a] = _wall_alias(_f)
    for _f in _PAIR_STATE:
        locals()[_f] = _pair_alias(_f)
    del _a, _f

    def __init__(self, *, scene, x, y, r, mass, inertia, v, om, mat, wall_geo, wall_mat, law, dt, dt_crit,
                 C, Cr, skin, gravity, track, material_names, box, fluid=None, dt_safe=None):
        self.scene = scene
        self.dt = dt
        self.dt_crit = dt_crit  # the single-spring estimate 2√(m_min/k_max), the base of dt_fraction
        self.dt_safe = dt_crit if dt_safe is None else dt_safe  # the packing's safe estimate (integrate.safe_time_step)
        self.dt_fluid = None  # the fluid drag limit of a saturated scene (set by build)
        self.skin = skin
        self.law = law  # the law family (demflow.laws), Python side
        self.law_params = law.params()  # what the compiled cycle reads
        self.box = box
        self.material_names = material_names
        self.gx, self.gy = gravity
        n = x.shape[0]
        self.n = n
        d = new_discs(n)
        d.x[:], d.y[:], d.vx[:], d.vy[:], d.om[:] = x, y, v[:, 0], v[:, 1], om
        d.r[:], d.mass[:], d.inertia[:], d.mat[:], d.C[:], d.Cr[:] = r, mass, inertia, mat, C, Cr
        self.discs = d
        self.ix = np.zeros(n, np.int64)  # periods crossed along x and y (periodic boxes)
        self.iy = np.zeros(n, np.int64)
        self._walls_init(scene, wall_geo, wall_mat)
        self.pairs = empty_pairs(law.history_width(2))
        self.track_a = np.array([a for a, _ in track], dtype=np.int64)
        self.track_b = np.array([b for _, b in track], dtype=np.int64)
        self.track = track
        self.step = 0
        self.disp_walls = 0.0
        self.rebuilds = 0
        self.layout = Layout(perm=np.arange(n, dtype=np.int64), inv=np.arange(n, dtype=np.int64),
                             P=np.zeros((n, 8)), Q=np.zeros((n, Q_WIDTH)), F=np.zeros((n, 3)))
        self.records = []
        self.snapshots = []
        # energy accounts of the running chunk (stepping.run_steps) and the last chunk's balance
        self._energy_acc = np.zeros(3)
        self._diss_discs = np.zeros(n)
        self._diss_pairs = np.zeros(0)
        self._wwork_pairs = np.zeros(0)
        self.energy_balance = None
        # saturated scenes only (thesis §3.4): the fluid coupling and the external force it feeds
        self.fluid = None
        self.has_external_force = False
        self.external_force = np.zeros((0, 3))
        self.dem_s = 0.0
        if fluid is not None:
            from .coupling import FluidCoupler

            self.fluid = FluidCoupler(self, fluid)
            self.has_external_force = True
            self.external_force = np.zeros((n, 3))
            # buoyancy B = -ρ_l A g, A = πR² (thesis eq 4.39)
            area = np.pi * r * r
            self._buoyancy = -fluid.rho * area[:, None] * np.array([self.gx, self.gy])[None, :]
            self._next_solve = self.fluid.setup.start
        self._scene_digest = scene_digest(self.fixed_parts())  # as built (demflow.checkpoint_scene)
        self._cell_side = (None, 0.0)  # (skin, neighbours.cell_side of the radii and that skin)
        self._inner_side = (None, 0.0)  # the same for the list's own skin (the slots' cell order)
        self._outer = None  # the wider pair list the builds filter (_pairs_from_outer_list)
        self.outer_builds = 0
        self.rebuild()

    def _walls_init(self, scene, wall_geo, wall_mat):
        self.nw = len(wall_geo)
        self.walls, self.loading = walls_and_loading(scene, wall_geo, wall_mat)
        self.wall_names = [w.name for w in scene.walls]

    # the linear law's parameters by their historical names
    @property
    def t(self) -> dict:
        """The law's per-material-pair tables (linear law: kn, ks, cn, cs, mu, coh)."""
        return self.law.tables()

    @property
    def has_shear(self) -> bool:
        return bool(self.law_params.has_shear)

    @property
    def n_hist(self) -> int:
        return self.pairs.hist.shape[1]

    # ------------------------------------------------------------------ contacts
    def wall_endpoints(self):
        """Endpoints (ax, ay, bx, by) of every wall segment, A = P + h1·e, B = P + h2·e [length]."""
        w = self.walls
        return w.px + w.h1 * w.ex, w.py + w.h1 * w.ey, w.px + w.h2 * w.ex, w.py + w.h2 * w.ey

    def unwrapped_positions(self):
        """Disc centres with the periods crossed added back (periodic boxes) [length]."""
        x, y = self.discs.x.copy(), self.discs.y.copy()
        if isinstance(self.box, PeriodicBox):
            if self.box.periodic_x:
                x += self.ix * self.box.lx
            if self.box.periodic_y:
                y += self.iy * self.box.ly
        return x, y

    def rebuild(self):
        """Rebuild the neighbour list from current positions, keeping contact history (keyed by pair).
        In a periodic box the centres are wrapped into the box first."""
        d = self.discs
        wrap(self.box, d.x, d.y, self.ix, self.iy)
        ax, ay, bx, by = self.wall_endpoints()
        # the steps run on the discs renumbered in spatial order (see stepping.run_steps): the cell order of the
        # search's own grid where there is one
        if isinstance(self.box, PeriodicBox):
            finder, other, sx, sy = pairs_periodic(d.x, d.y, d.r, self.skin, ax, ay, bx, by, self.box)
            perm = spatial_order(d.x, d.y, d.r, self.skin)
        else:
            finder, other, perm = self._pairs_from_outer_list(ax, ay, bx, by)
            sx = sy = np.empty(0)
        old = self.pairs
        hist = transfer_history(old.finder, old.other, old.hist, finder, other, self.n + self.nw)
        self._install_pairs(finder, other, hist, sx, sy, perm)
        d.xref[:] = d.x
        d.yref[:] = d.y
        self.disp_walls = 0.0
        self.rebuilds += 1

    def _pairs_from_outer_list(self, ax, ay, bx, by):
        """(finder, other, perm) of a neighbour-list build in a box without periodic axes: the pairs with gap below
        the skin, key order, exactly those of :func:`pairs_cell_search_ordered` with this skin, and a spatial order.

        Taken from a wider list (gap below OUTER_SKIN × skin, built by the cell search) while that list still holds
        every pair the cell search would list (:func:`outer_list_holds`: the discs and walls moved little enough
        since its build), by one pass over it (:func:`pairs_within`); otherwise the wider list is built anew first.
        At 1e5 discs the cell search took 18-20 ms of a 28 ms build and the pass takes about 2 ms; at OUTER_SKIN = 4
        three wider lists served the 13 builds of 400 steps there (speed_experiments_session49.md).  The wider list
        costs about 64 bytes a disc there (3 pairs a disc and the centres at its build).  The slots' order is the
        cell order of this skin's grid, as the cell search gives it (keeping the wider grid's order, which only
        sets speed, made the steps 6 % slower there).
        """
        d = self.discs
        so = OUTER_SKIN * self.skin
        o = self._outer
        if o is None or o["skin"] != self.skin or not outer_list_holds(
                self.skin, so, d.x, d.y, o["x"], o["y"], ax, ay, bx, by, *o["walls"]):
            if self._cell_side[0] != so:  # the radii are fixed at construction; the side follows the skin
                self._cell_side = (so, cell_side(d.r, so))
            fo, oo, _ = pairs_cell_search_ordered(d.x, d.y, d.r, so, ax, ay, bx, by, self._cell_side[1])
            o = self._outer = dict(skin=self.skin, finder=fo, other=oo, x=d.x.copy(), y=d.y.copy(),
                                   walls=(ax.copy(), ay.copy(), bx.copy(), by.copy()))
            self.outer_builds += 1
        finder, other = pairs_within(o["finder"], o["other"], d.x, d.y, d.r, self.skin, ax, ay, bx, by)
        if self._inner_side[0] != self.skin:
            self._inner_side = (self.skin, cell_side(d.r, self.skin))
        return finder, other, cell_order(d.x, d.y, self._inner_side[1])

    def _disc_rows(self) -> np.ndarray:
        """The discs' packed rows P (n, 8) in disc order, for :func:`pair_forces` on the key-order pair list
        (:func:`demflow.integrate.pack_rows` in the identity order; its Q and F rows are not kept)."""
        n = self.n
        P = np.empty((n, 8))
        pack_rows(self.discs, np.arange(n, dtype=np.int64), P, np.empty((n, Q_WIDTH)), np.empty((n, 3)))
        return P

    def _install_pairs(self, finder, other, hist, sx, sy, perm):
        """Make (finder, other) with its history and periodic shifts (key order) the pair list, and ``perm``
        the discs' spatial order, with every array the steps derive from them."""
        inv, pos, fin_p, oth_p, start_p, sidx_p, wall_p = internal_layout(finder, other, self.n, perm, self.n + self.nw)
        sx_p, sy_p = np.empty_like(sx), np.empty_like(sy)
        sx_p[pos[:sx.shape[0]]] = sx
        sy_p[pos[:sy.shape[0]]] = sy
        m = finder.shape[0]
        self._diss_pairs = np.zeros(finder.shape[0])
        self._wwork_pairs = np.zeros(finder.shape[0])
        self.pairs = Pairs(finder=finder, other=other, hist=hist, sx=sx, sy=sy, pos=pos, fin_p=fin_p, oth_p=oth_p,
                           hist_p=np.empty_like(hist), sx_p=sx_p, sy_p=sy_p, start_p=start_p, sidx_p=sidx_p,
                           wall_p=wall_p, f=np.zeros((m, 3)), out=pair_outputs(m))
        self.layout = self.layout._replace(perm=perm, inv=inv)

    # ------------------------------------------------------------------ running
    def run(self, n_steps: int | None = None, *, checkpoint: str | os.PathLike | None = None,
            checkpoint_every: int | None = None, threads: int | None = None,
            progress: bool | None = None) -> "Simulation":
        """See :meth:`_run`; ``threads`` (default: 1 below PARALLEL_MIN_DISCS discs, else all
        set by :func:`demflow.jit.set_threads`) only changes speed, never results.  ``progress``: a
        bar (True), none (False), or :mod:`demflow.progress`'s rule (None: on a terminal, after a few
        seconds)."""
        import numba

        from .progress import bar as progress_bar

        if threads is not None:
            check_thread_count("run(threads)", threads)  # (more than this machine has: capped, results unchanged)
        if checkpoint_every is not None:
            check_whole("run(checkpoint_every)", checkpoint_every, ge=1)
        before = numba.get_num_threads()
        want = threads or (1 if self.n < self.PARALLEL_MIN_DISCS else before)
        numba.set_num_threads(min(want, numba.config.NUMBA_NUM_THREADS))
        total = max(int(self.scene.n_steps) - self.step, 0) if n_steps is None else n_steps
        try:
            with progress_bar(total if isinstance(total, int) else 0, self.scene.name, show=progress) as bar:
                self._bar = bar
                return self._run(n_steps, checkpoint=checkpoint, checkpoint_every=checkpoint_every)
        finally:
            self._bar = None
            numba.set_num_threads(before)

    def _run(self, n_steps: int | None = None, *, checkpoint: str | os.PathLike | None = None,
             checkpoint_every: int | None = None) -> "Simulation":
        """Advance ``n_steps`` steps (default: the scene's n_steps minus steps done).

        Snapshots declared in the scene are taken when their step is reached.  With
        ``checkpoint`` a resumable state is written atomically every ``checkpoint_every``
        steps and at the end.  A blow-up raises :class:`BlowUpError` after saving the
        last good state.
        """
        if n_steps is None:
            n_steps = max(int(self.scene.n_steps) - self.step, 0)
        n_steps = check_whole("run(n_steps)", n_steps)
        nt = len(self.track)
        check_run_length("run(n_steps)", n_steps, self.scene, self.n, self.nw, nt, self.step)
        target = self.step + n_steps
        every = int(self.scene.outputs.every)
        # the records of one chunk (at most CHUNK steps); each chunk's rows are kept as it ends, so memory
        # grows with what is recorded, not with the run length
        nrec = (min(n_steps, self.CHUNK) // every + 2) if every > 0 else 0
        rec = Records(every=every, step=np.zeros(nrec, np.int64), wall=np.zeros((nrec, self.nw, 3)),
                      wallpos=np.zeros((nrec, self.nw, 2)), track_a=self.track_a, track_b=self.track_b,
                      track=np.zeros((nrec, nt, 2)), energy=np.zeros((nrec, 2)))
        rec_count = 0
        pieces = []
        snaps = sorted(s for s in self.scene.outputs.snapshots if self.step <= s <= target)
        last_ckpt = self.step
        changes = sorted({int(st) for w in self.scene.walls if w.servo is not None for st, _ in w.servo.schedule})
        while True:
            while snaps and snaps[0] == self.step:
                self._take_snapshot()
                snaps.pop(0)
            if self.step >= target:
                break
            self._set_servo_targets()
            nxt = [c for c in changes if c > self.step]
            stop = min(target, snaps[0] if snaps else target, self.step + self.CHUNK, nxt[0] if nxt else target)
            good = self._copy_state()
            balance = self._balance_open()
            while self.step < stop:
                n_run = stop - self.step
                if self.fluid is not None:
                    if self.step >= self._next_solve:
                        self._fluid_update()
                        bad = first_nonfinite({"the fluid force and buoyancy (external_force)": self.external_force})
                        if bad:
                            self._blow_up(good, pieces, rec, rec_count, f"{bad} is not finite after the fluid solve")
                    n_run = min(n_run, self._next_solve - self.step)
                t_dem = time.perf_counter()
                if self.has_external_force:
                    before = (self.discs.x.copy(), self.discs.y.copy(), self.discs.th.copy())
                done, status, self.disp_walls, rec_count = run_steps(
                    n_run, self.step, self.skin, self.disp_walls, self.discs, self.layout,
                    self.pairs, self.walls, self.loading, self.law_params, self.box, self.dt, self.gx, self.gy,
                    rec, rec_count, self.external_force, self.has_external_force, self._energy_acc,
                    self._diss_pairs, self._wwork_pairs, self._diss_discs)
                if self.has_external_force:  # the external force is held over the call: its work is F·Δx
                    d, e = self.discs, self.external_force
                    balance["external"] += float(np.sum(e[:, 0] * (d.x - before[0]) + e[:, 1] * (d.y - before[1])
                                                        + e[:, 2] * (d.th - before[2])))
                self.dem_s += time.perf_counter() - t_dem
                self.step += done
                if self._bar is not None:
                    self._bar.update(done)
                # BLOWUP: an overlap, jump or contact force test failed; NONFINITE: the state on return holds
                # a NaN or inf no contact saw (a disc in free flight under a NaN gravity or external force, a
                # wall driven to infinity), found by one O(n) pass per call of the cycle, per chunk or
                # neighbour-list rebuild, never per pair per step (cost: benchmarks/results/nonfinite_check.md)
                if status in (BLOWUP, NONFINITE):
                    self._blow_up(good, pieces, rec, rec_count, None)
                if status == REBUILD:
                    self.rebuild()
            why = self._balance_close(balance)
            if why and self.scene.energy_check == "warn":
                warnings.warn(f"scene {self.scene.name!r}: {why} (energy_check='warn': the run goes on)",
                              EnergyBalanceWarning, stacklevel=3)
            elif why:
                self._blow_up(good, pieces, rec, rec_count, None, why=why)
            rec_count = self._keep_records(pieces, rec, rec_count)
            if checkpoint is not None and checkpoint_every and self.step - last_ckpt >= checkpoint_every:
                self.save_checkpoint(checkpoint)
                last_ckpt = self.step
        self._store_records(pieces)
        if checkpoint is not None:
            self.save_checkpoint(checkpoint)
        return self

    def _nonfinite_state(self) -> str | None:
        """The first non-finite quantity of the dynamic state (disc positions, rotations, velocities and
        contact force sums, wall points, directions, velocities and forces, contact history), or None."""
        d, w = self.discs, self.walls
        if state_is_finite(d, w, self.pairs.hist):  # the compiled screen; the names only when it fails
            return None
        return first_nonfinite({
            "discs.x": d.x, "discs.y": d.y, "discs.vx": d.vx, "discs.vy": d.vy, "discs.om": d.om,
            "discs.th": d.th, "discs.Fx": d.Fx, "discs.Fy": d.Fy, "discs.M": d.M,
            "walls.px": w.px, "walls.py": w.py, "walls.ex": w.ex, "walls.ey": w.ey, "walls.vx": w.vx,
            "walls.vy": w.vy, "walls.om": w.om, "walls.cx": w.cx, "walls.cy": w.cy, "walls.force": w.force,
            "pairs.hist": self.pairs.hist})

    # ------------------------------------------------------------------ energy balance
    def mechanical_energy(self) -> dict:
        """The energy of the current state (step n: positions x_n, velocities v_{n-1/2}) as the balance
        counts it [force·length]:

        - ``kinetic``: ½Σ(m v_{n-1/2}·v_{n+1/2} + I ω_{n-1/2} ω_{n+1/2}), the product of the half-step
          velocities either side of step n (v_{n+1/2} predicted from the forces at step n): with it the
          change of kinetic energy over a step is exactly the mean of the step's end forces times its
          displacement, so that gravity's work m g·Δx and a linear spring's ½kΔδ² close to round-off;
        - ``elastic``: the springs at step n (the pair forces evaluated on a copy of the history, as
          :meth:`contact_table_arrays` does: a fresh overlap-law contact counts from the start);
        - ``dissipated`` and ``work_walls``: what that evaluation's step will add to the accounts (the
          next chunk counts them again: they cancel across chunks).
        """
        d = self.discs
        n = self.n
        pr = self.pairs
        m = pr.finder.shape[0]
        P = self._disc_rows()
        h = pr.hist.copy()
        f = np.zeros((m, 3))  # each pair's force on its finder and its shear force (fx, fy, Fs)
        diss, wwork = np.zeros(m), np.zeros(m)
        if m:
            pair_forces(pr.finder, pr.other, h, pr.sx, pr.sy, P, n, self.walls, self.law_params, self.box, self.dt,
                        f, False, *pair_outputs(m), np.inf, diss, wwork, NO_PAIRS, False)
        # each disc's force and moment sums at step n (as demflow.integrate.sum_and_integrate), then v_{n+1/2}
        # each disc's share: (fx, fy, Fs·R) as the finder, (-fx, -fy, Fs·R) as the other disc
        fx, fy, mo = force_sums_keys(pr.finder, pr.other, f, d.r, n)
        if self.has_external_force:
            fx, fy, mo = fx + self.external_force[:, 0], fy + self.external_force[:, 1], mo + self.external_force[:, 2]
        dt = self.dt
        a = d.C * dt / (2.0 * d.mass)
        b = d.Cr * dt / (2.0 * d.inertia)
        vx = (d.vx * (1.0 - a) + (fx / d.mass + self.gx) * dt) / (1.0 + a)
        vy = (d.vy * (1.0 - a) + (fy / d.mass + self.gy) * dt) / (1.0 + a)
        om = (d.om * (1.0 - b) + mo * dt / d.inertia) / (1.0 + b)
        ke = float(0.5 * np.sum(d.mass * (d.vx * vx + d.vy * vy) + d.inertia * d.om * om))
        el = float(elastic_energy_keys(pr.finder, pr.other, h, d.mat, self.walls.mat, n, self.law_params)) if m else 0.0
        return dict(kinetic=ke, elastic=el, dissipated=float(diss.sum()), work_walls=float(wwork.sum()))

    def _balance_open(self) -> dict:
        """Start the energy balance of a chunk: the energy now (:meth:`mechanical_energy`), the unwrapped
        positions, and the accounts (dissipation, wall work, external work) at zero."""
        self._energy_acc[:] = 0.0
        x, y = self.unwrapped_positions()
        return dict(step=self.step, now=self.mechanical_energy(), x=x, y=y, external=0.0)

    def _balance_close(self, b: dict) -> str | None:
        """Close a chunk's energy balance (issue 17): the energy the steps created,

            created = Δ(kinetic + elastic) + dissipated (dashpots, friction, global damping)
                      - work of the walls - work of gravity - work of external (fluid) forces,

        is round-off and O(Δt) discretisation in a stable run; an unstable step creates it (and friction can
        dissipate it as fast, so that overlaps stay small).  Returns why the chunk blew up, or None; keeps
        the numbers in ``energy_balance``."""
        if self.step == b["step"]:
            return None
        now0, now1 = b["now"], self.mechanical_energy()
        x, y = self.unwrapped_positions()
        d = self.discs
        gravity = float(np.sum(d.mass * (self.gx * (x - b["x"]) + self.gy * (y - b["y"]))))
        contacts, damping, walls = (float(v) for v in self._energy_acc)
        # the accounts are one pair evaluation behind the energy (mechanical_energy): shift them
        contacts += now1["dissipated"] - now0["dissipated"]
        walls += now1["work_walls"] - now0["work_walls"]
        e0 = now0["kinetic"] + now0["elastic"]
        e1 = now1["kinetic"] + now1["elastic"]
        created = (e1 - e0) + contacts + damping - walls - gravity - b["external"]
        supplied = abs(e0) + abs(walls) + abs(gravity) + abs(b["external"])
        self.energy_balance = dict(start=b["step"], end=self.step, energy_start=e0, energy_end=e1,
                                   dissipated_contacts=contacts, dissipated_damping=damping, work_walls=walls,
                                   work_gravity=gravity, work_external=b["external"], created=created,
                                   supplied=supplied)
        limit = tol("energy.blow-up").value
        if math.isfinite(created) and (created <= limit * supplied or created <= ENERGY_ROUND_OFF * (e1 + contacts + damping)):
            return None
        return (f"the energy balance of steps {b['step']}-{self.step} does not close: the steps created {created:.6g} "
                f"(Δ(kinetic + elastic) {e1 - e0:.6g} + dissipated {contacts + damping:.6g} - work of walls "
                f"{walls:.6g}, gravity {gravity:.6g} and external forces {b['external']:.6g}), more than "
                f"{limit:g} × the {supplied:.6g} the chunk started with or was given (tolerance 'energy.blow-up', "
                f"demflow/tolerances.py): the time step is unstable. Reduce dt ({self._dt_advice()})")

    def _dt_advice(self) -> str:
        """The time steps a blow-up message quotes: the current one and the limits build knew of."""
        s = f"now {self.dt:.4g}, safe estimate {self.dt_safe:.4g} (demflow.integrate.safe_time_step)"
        if self.dt_fluid is not None:
            s += f", fluid drag limit {self.dt_fluid:.4g} (demflow.coupling)"
        return s

    def _blow_up(self, good, pieces, rec, rec_count, what, why=None):
        """Keep the records so far, restore the last good state ``good``, save it and raise BlowUpError;
        ``what`` names a non-finite quantity (None: the cycle stopped on its own tests, BLOWUP or NONFINITE,
        and the state is searched for the quantity to name); ``why`` (the energy balance) replaces the
        message's reason."""
        if what is None and why is None:  # name the non-finite quantity, if there is one
            bad = self._nonfinite_state()
            what = f"{bad} is not finite" if bad else None
        self._keep_records(pieces, rec, rec_count)
        self._store_records(pieces)
        bad_step = self.step
        self._restore_state(good)
        path = self._save_last_good()
        if why is None and what is None:
            why = (f"a contact overlapped more than {MAX_OVERLAP_RATIO:.0%} of a radius, a disc moved more than "
                   f"{MAX_STEP_RATIO:.0%} of its radius in one step, or a force became non-finite. Reduce dt "
                   f"({self._dt_advice()}) or the loading rate")
        elif why is None:
            why = (f"{what} (its origin may be gravity (now ({self.gx}, {self.gy})), an external or fluid force, a "
                   f"contact law or a wall's motion). Check those for NaN or infinite values, then reduce dt (now "
                   f"{self.dt:.4g}, critical estimate {self.dt_crit:.4g}) or the loading rate")
        raise BlowUpError(f"scene {self.scene.name!r} blew up at step {bad_step}: {why}. Last good state "
                          f"(step {self.step}) saved to {path}", path)

    @staticmethod
    def _keep_records(pieces, rec, q) -> int:
        """Move the first ``q`` rows of the chunk records ``rec`` into ``pieces``; returns 0 (the new count)."""
        if q:
            pieces.append((rec.step[:q].copy(), rec.wall[:q].copy(), rec.wallpos[:q].copy(), rec.track[:q].copy(),
                           rec.energy[:q].copy()))
        return 0

    def _set_servo_targets(self):
        """Servo targets F_A in effect at the current step (Servo.schedule)."""
        for w, wall in enumerate(self.scene.walls):
            if wall.servo is not None:
                self.loading.servo_F[w] = wall.servo.force_at(self.step)

    def _fluid_update(self):
        """Solve the fluid at the current state (positions x_i, velocities v_{i-1/2}: the half-step
        lag of thesis §3.4) and hold its force, moment and the buoyancy (eq 4.39) for the next
        stride (see :mod:`demflow.coupling`)."""
        f = self.fluid
        out = f.solve(self)
        if not f.setup.moments:
            out[:, 2] = 0.0
        out[:, :2] += self._buoyancy
        self.external_force[:] = out
        k = f.stable_stride(self)
        f.strides.append((self.step, k))
        self._next_solve = self.step + k

    def _store_records(self, pieces):
        """One run's records, its chunks joined, as one entry of ``records``."""
        if pieces:
            self.records.append(tuple(np.concatenate(parts) for parts in zip(*pieces)))

    # ------------------------------------------------------------------ snapshots
    def contact_table_arrays(self):
        """Contact forces at the current step, computed without advancing history.

        Returns a dict of arrays for pairs in contact: finder, other, px, py, nx, ny
        (ε, from finder to other), fn, fs, sliding, overlap.
        """
        pr = self.pairs
        m = pr.finder.shape[0]
        P = self._disc_rows()
        out = pair_outputs(m)
        pair_forces(pr.finder, pr.other, pr.hist.copy(), pr.sx, pr.sy, P, self.n, self.walls, self.law_params,
                    self.box, self.dt, np.zeros((m, 3)), True, *out, np.inf, np.zeros(m),
                    np.zeros(m), NO_PAIRS, False)
        fn, fs, slide, ovl, cpx, cpy = out
        on = ovl > 0
        i, j = self.finder[on], self.other[on]
        px, py = cpx[on], cpy[on]
        # ε from the finder's centre through the contact point (it lies on that line)
        gex, gey = px - self.x[i], py - self.y[i]
        L = np.hypot(gex, gey)
        ex, ey = gex / L, gey / L
        f_n, f_s = fn[on], fs[on]
        return dict(finder=i, other=j, px=px, py=py, nx=ex, ny=ey, fn=f_n, fs=f_s,
                    sliding=slide[on].astype(bool), overlap=ovl[on])

    def _take_snapshot(self):
        c = self.contact_table_arrays()
        self.snapshots.append(dict(
            step=self.step, time=self.step * self.dt,
            particles=dict(x=self.x.copy(), y=self.y.copy(), theta=self.th.copy(), vx=self.vx.copy(),
                           vy=self.vy.copy(), omega=self.om.copy(), radius=self.r.copy()),
            walls=dict(px=self.wpx.copy(), py=self.wpy.copy(), ex=self.wex.copy(), ey=self.wey.copy(),
                       h1=self.wh1.copy(), h2=self.wh2.copy()),
            contacts=c))

    def snapshot_now(self):
        """Record a snapshot at the current step (in addition to the scene's)."""
        self._take_snapshot()
        return self

    # ------------------------------------------------------------------ results
    def results(self):
        """The run's tables (see :class:`demflow.results.Results`)."""
        from .results import Results

        return Results.from_simulation(self)

    # ------------------------------------------------------------------ state I/O
    def _state_arrays(self) -> dict:
        """The dynamic state by name (the arrays themselves, not copies): discs, walls, the pair list with its
        history, and what makes the list's next steps those of a run that never stopped (its periodic shifts, the
        discs' spatial order and positions at the list's build, the walls' travel since: :data:`_LIST_STATE`)."""
        out = {k: getattr(self.discs, k) for k in _DISC_STATE}
        out.update({k: getattr(self.walls, f) for k, f in _WALL_STATE.items()})
        out.update({k: getattr(self.pairs, k) for k in _PAIR_STATE})
        if isinstance(self.box, PeriodicBox):
            out.update(ix=self.ix, iy=self.iy)
        out.update(sx=self.pairs.sx, sy=self.pairs.sy, perm=self.layout.perm, xref=self.discs.xref,
                   yref=self.discs.yref, disp_walls=np.array([self.disp_walls]))
        return out

    def _set_state(self, s: dict, relist: bool = False) -> None:
        """Take over the state ``s`` (arrays by name, as :meth:`_state_arrays`).

        A state with the pair list's build (:data:`_LIST_STATE`: a checkpoint, the last good state) gets its list back
        as it was, with no rebuild, so that the run goes on with the same list, the same rebuild steps and the same
        periodic wraps as one never stopped (a rebuild here would wrap and re-list at another step: x - L + v·dt and
        x + v·dt - L round differently, and a packing is chaotic).  With ``relist`` (another stage's state, see
        :meth:`continue_from`) or a checkpoint written before 2026-11-27 the list is rebuilt from the positions."""
        for k in _DISC_STATE:
            getattr(self.discs, k)[:] = s[k]
        for k, f in _WALL_STATE.items():
            getattr(self.walls, f)[:] = s[k]
        if "ix" in s:
            self.ix[:] = s["ix"]
            self.iy[:] = s["iy"]
        finder = np.array(s["finder"], np.int64)
        other = np.array(s["other"], np.int64)
        hist = np.array(s["hist"], np.float64)
        if relist or any(k not in s for k in _LIST_STATE):
            self.pairs = empty_pairs(hist.shape[1])._replace(finder=finder, other=other, hist=hist)
            self.rebuild()
            return
        self._install_pairs(finder, other, hist, np.array(s["sx"], np.float64), np.array(s["sy"], np.float64),
                            np.array(s["perm"], np.int64))
        self.discs.xref[:] = s["xref"]
        self.discs.yref[:] = s["yref"]
        self.disp_walls = float(s["disp_walls"][0])

    def _copy_state(self):
        return {k: v.copy() for k, v in self._state_arrays().items()} | {"step": self.step}

    def _restore_state(self, s):
        self.step = s["step"]
        if self.fluid is not None:
            self._next_solve = max(self.step, self.fluid.setup.start)
        self._set_state(s)

    def _save_last_good(self):
        path = last_good_path(self.scene.name, self.step)
        self.save_checkpoint(path)
        return str(path)

    def save_checkpoint(self, path: str | os.PathLike) -> Path:
        """Write the dynamic state to ``path`` (.npz) atomically (temp file + rename)."""
        meta = dict(scene=self.scene.name, step=self.step, n=self.n, nw=self.nw, dt=self.dt,
                    static=self._scene_digest)
        return write_checkpoint(Path(path), meta, self._state_arrays())

    def fixed_parts(self) -> dict:
        """What the scene fixes and a run does not change, by name (:mod:`demflow.checkpoint_scene`): a checkpoint
        continues only a simulation where these are the same."""
        d, w = self.discs, self.walls
        return {"discs (radius, mass, inertia, damping, material)": (d.r, d.mass, d.inertia, d.C, d.Cr, d.mat),
                "walls (extent, material)": (w.h1, w.h2, w.mat), "time step": self.dt,
                "gravity": (self.gx, self.gy), "contact law": self.law_params, "box": repr(self.box),
                "fluid": repr(self.scene.fluid)}

    def continue_from(self, other: "Simulation") -> "Simulation":
        """Take over ``other``'s dynamic state as this scene's step 0: disc positions, rotations and
        velocities, wall positions and velocities, and every contact with its history (keyed by
        pair).  A protocol in stages whose laws or loading differ (a frictionless compression, then
        frictional shear; a dry stage, then a saturated one) keeps its contact forces across the
        change.  The scenes must have the same discs (radii) and the same number of walls."""
        if other.n != self.n or other.nw != self.nw or not np.array_equal(other.r, self.r):
            raise ValueError(
                f"continue_from: scene {other.scene.name!r} has {other.n} discs and {other.nw} walls, "
                f"{self.scene.name!r} has {self.n} and {self.nw} (or the radii differ); a staged protocol "
                "needs the same discs and walls in every stage")
        state = other._state_arrays()
        # a stage with another law or history width keeps what the law carries over (demflow.laws.base)
        state["hist"] = self.law.continue_from(other.pairs.hist, self.n_hist)
        # the discs' forces on the walls as the other stage left them: a saturated stage's first solve
        # hands F_A − F_C to the fluid (thesis §5.3.2) before its first step computes them again
        self.step = 0
        if self.fluid is not None:
            self._next_solve = self.fluid.setup.start
        self._set_state(state, relist=True)
        self.walls.force[:] = other.walls.force
        return self

    def load_checkpoint(self, path: str | os.PathLike) -> "Simulation":
        """Restore a state written by :meth:`save_checkpoint` for the same scene."""
        meta, state = read_checkpoint(path)
        if meta["scene"] != self.scene.name or meta["n"] != self.n or meta["nw"] != self.nw:
            raise ValueError(
                f"checkpoint {path} is for scene {meta['scene']!r} with {meta['n']} discs and "
                f"{meta['nw']} walls, not {self.scene.name!r} ({self.n}, {self.nw}); build the same scene"
            )
        check_same_scene(path, meta, self._scene_digest)
        self.step = int(meta["step"])
        if self.fluid is not None:
            self._next_solve = max(self.step, self.fluid.setup.start)
        self._set_state(state)
        return self
