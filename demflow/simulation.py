"""A built simulation: structure-of-arrays state plus the compiled calculation cycle.

Created by :func:`demflow.build.build`; never construct it by hand.  ``run`` advances it,
``results`` returns the tables, ``save_checkpoint``/``load_checkpoint`` make long runs
resumable (atomic writes).
"""
from __future__ import annotations

import json
import os
import tempfile
import time
from pathlib import Path

import numpy as np

from .contacts.forces import contact_forces
from .contacts.neighbours import (contacts_of_particles_signed, internal_layout, pairs_cell_search,
                                  spatial_order, transfer_history)
from .stepping import BLOWUP, MAX_OVERLAP_RATIO, MAX_STEP_RATIO, REBUILD, run_steps


class BlowUpError(RuntimeError):
    """The run became unstable; ``path`` holds the last good state."""

    def __init__(self, message: str, path: str | None):
        super().__init__(message)
        self.path = path


# arrays that make up the dynamic state (what a checkpoint stores)
_STATE = ("x", "y", "th", "vx", "vy", "om", "wpx", "wpy", "wex", "wey", "wvx", "wvy", "wom",
          "wcx", "wcy", "finder", "other", "hist")


class Simulation:
    """State and stepping of one 2D disc scene (see :mod:`demflow.build`)."""

    CHUNK = 20000  # steps between last-good-state copies
    # Below this many discs a step is too short to share between threads: on this 2-core
    # machine the nine-disc test ran 65× slower on 2 threads than on 1 (4.06 s vs 0.063 s,
    # 9040 steps); benchmarks/results/crossover.md: 2 threads pay off above ~4000 discs
    # (0.91× at 4000, 1.74× at 10000).
    PARALLEL_MIN_DISCS = 8000

    def __init__(self, *, scene, x, y, r, mass, inertia, v, om, mat, wall_geo, wall_mat, tables,
                 has_shear, dt, dt_crit, C, Cr, skin, gravity, normal_mode, sliding_mode, track,
                 material_names, fluid=None):
        self.scene = scene
        self.dt = dt
        self.dt_crit = dt_crit
        self.dt_fluid = None  # the fluid drag limit of a saturated scene (set by build)
        self.skin = skin
        self.has_shear = has_shear
        self.normal_mode = normal_mode
        self.sliding_mode = sliding_mode
        self.material_names = material_names
        self.gx, self.gy = gravity
        n = x.shape[0]
        self.n = n
        self.x, self.y = x.copy(), y.copy()
        self.th = np.zeros(n)
        self.vx, self.vy = v[:, 0].copy(), v[:, 1].copy()
        self.om = om.copy()
        self.r, self.mass, self.inertia, self.mat = r, mass, inertia, mat
        self.C, self.Cr = C, Cr
        self.t = tables
        # walls
        nw = len(wall_geo)
        self.nw = nw
        g = np.array(wall_geo, dtype=np.float64).reshape(nw, 8)
        self.wpx, self.wpy = g[:, 4].copy(), g[:, 5].copy()
        self.wex, self.wey = g[:, 6].copy(), g[:, 7].copy()
        self.wh1 = np.array([w.h1 for w in scene.walls], dtype=np.float64)
        self.wh2 = np.array([w.h2 for w in scene.walls], dtype=np.float64)
        self.wvx, self.wvy, self.wom = np.zeros(nw), np.zeros(nw), np.zeros(nw)
        self.wcx, self.wcy = self.wpx.copy(), self.wpy.copy()
        self.wmat = wall_mat
        self.wall_force = np.zeros((nw, 3))
        self.wall_names = [w.name for w in scene.walls]
        K = max([len(w.phases) for w in scene.walls], default=0) or 1
        self.phase_start = np.zeros((nw, K), np.int64)
        self.phase_end = np.zeros((nw, K), np.int64)
        self.phase_vx, self.phase_vy, self.phase_om = (np.zeros((nw, K)) for _ in range(3))
        self.phase_cx, self.phase_cy = np.zeros((nw, K)), np.zeros((nw, K))
        self.phase_about_p = np.ones((nw, K), np.int8)
        for w, wall in enumerate(scene.walls):
            s0 = 0
            for k, ph in enumerate(wall.phases):
                self.phase_start[w, k] = s0
                self.phase_end[w, k] = s0 + int(ph.cycles)
                s0 += int(ph.cycles)
                self.phase_vx[w, k], self.phase_vy[w, k] = map(float, ph.velocity)
                self.phase_om[w, k] = float(ph.omega)
                if ph.pivot is not None:
                    self.phase_about_p[w, k] = 0
                    self.phase_cx[w, k], self.phase_cy[w, k] = map(float, ph.pivot)
        self.servo_on = np.zeros(nw, np.int8)
        self.servo_start = np.zeros(nw, np.int64)
        self.servo_F, self.servo_dx, self.servo_dy, self.servo_G, self.servo_vmax = (
            np.zeros(nw) for _ in range(5))
        for w, wall in enumerate(scene.walls):
            if wall.servo is not None:
                s = wall.servo
                L = float(np.hypot(*s.direction))
                self.servo_on[w] = 1
                self.servo_start[w] = s.start
                self.servo_F[w] = s.force
                self.servo_dx[w], self.servo_dy[w] = s.direction[0] / L, s.direction[1] / L
                self.servo_G[w], self.servo_vmax[w] = s.gain, s.v_max
        # contacts: history has a shear column only when some law has a shear spring
        self.n_hist = 2 if has_shear else 1
        self.finder = np.empty(0, np.int64)
        self.other = np.empty(0, np.int64)
        self.hist = np.zeros((0, self.n_hist))
        self.track_a = np.array([a for a, _ in track], dtype=np.int64)
        self.track_b = np.array([b for _, b in track], dtype=np.int64)
        self.track = track
        self.step = 0
        self.disp_walls = 0.0
        self.rebuilds = 0
        self._P = np.zeros((n, 8))  # packed disc rows for the pair-force kernel
        self._Fx, self._Fy, self._M = (np.zeros(n) for _ in range(3))  # last step's force sums
        # by slot: x, y, th, vx, vy, om, xref, yref, Fx, Fy, M
        self._slots = tuple(np.zeros(n) for _ in range(11))
        self._r_p, self._mass_p, self._inertia_p, self._C_p, self._Cr_p = (np.zeros(n) for _ in range(5))
        self._mat_p = np.zeros(n, np.int64)
        self.records = []
        self.snapshots = []
        # saturated scenes only (thesis §3.4): the fluid coupling and the external force it feeds
        self.fluid = None
        self._has_ext = False
        self._ext = np.zeros((0, 3))
        self.dem_s = 0.0
        if fluid is not None:
            from .coupling import FluidCoupler

            self.fluid = FluidCoupler(self, fluid)
            self._has_ext = True
            self._ext = np.zeros((n, 3))
            # buoyancy B = -ρ_l A g, A = πR² (thesis eq 4.39)
            area = np.pi * r * r
            self._buoyancy = -fluid.rho * area[:, None] * np.array([self.gx, self.gy])[None, :]
            self._next_solve = self.fluid.setup.start
        self.rebuild()

    # ------------------------------------------------------------------ contacts
    def wall_endpoints(self):
        """Endpoints (ax, ay, bx, by) of every wall segment, A = P + h1·e, B = P + h2·e [length]."""
        ax = self.wpx + self.wh1 * self.wex
        ay = self.wpy + self.wh1 * self.wey
        bx = self.wpx + self.wh2 * self.wex
        by = self.wpy + self.wh2 * self.wey
        return ax, ay, bx, by

    def rebuild(self):
        """Rebuild the neighbour list from current positions, keeping contact history."""
        ax, ay, bx, by = self.wall_endpoints()
        finder, other = pairs_cell_search(self.x, self.y, self.r, self.skin, ax, ay, bx, by)
        self.hist = transfer_history(self.finder, self.other, self.hist, finder, other, self.n + self.nw)
        self.finder, self.other = finder, other
        start, sidx = contacts_of_particles_signed(finder, other, self.n)
        wall_pairs = np.flatnonzero(other >= self.n).astype(np.int64)
        # the steps run on the discs renumbered in spatial order (see stepping.run_steps)
        self._perm = spatial_order(self.x, self.y, self.r, self.skin)
        (self._inv, self._pos, self._fin_p, self._oth_p, self._start_p, self._sidx_p,
         self._wall_p) = internal_layout(finder, other, self.n, self._perm, start, sidx, wall_pairs)
        m = finder.shape[0]
        self._hist_p = np.empty_like(self.hist)
        self._f = np.zeros((m, 3))  # (fx, fy, Fs) per pair, the per-step work array
        self._fn, self._fs, self._ovl, self._cpx, self._cpy = (np.zeros(m) for _ in range(5))
        self._slide = np.zeros(m, np.int8)
        self.xref, self.yref = self.x.copy(), self.y.copy()
        self.disp_walls = 0.0
        self.rebuilds += 1

    def _law_args(self):
        t = self.t
        return (t["kn"], t["ks"], t["cn"], t["cs"], t["mu"], t["coh"], self.dt,
                self.normal_mode, self.sliding_mode, self.has_shear)

    # ------------------------------------------------------------------ running
    def run(self, n_steps: int | None = None, *, checkpoint: str | os.PathLike | None = None,
            checkpoint_every: int | None = None, threads: int | None = None) -> "Simulation":
        """See :meth:`_run`; ``threads`` (default: 1 below PARALLEL_MIN_DISCS discs, else all
        set by :func:`demflow.jit.set_threads`) only changes speed, never results."""
        import numba

        before = numba.get_num_threads()
        want = threads or (1 if self.n < self.PARALLEL_MIN_DISCS else before)
        numba.set_num_threads(min(want, numba.config.NUMBA_NUM_THREADS))
        try:
            return self._run(n_steps, checkpoint=checkpoint, checkpoint_every=checkpoint_every)
        finally:
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
            n_steps = max(self.scene.n_steps - self.step, 0)
        target = self.step + int(n_steps)
        every = int(self.scene.outputs.every)
        nrec = (n_steps // every + 2) if every > 0 else 0
        nt = len(self.track)
        rec_step = np.zeros(nrec, np.int64)
        rec_wall = np.zeros((nrec, self.nw, 3))
        rec_wallpos = np.zeros((nrec, self.nw, 2))
        rec_track = np.zeros((nrec, nt, 2))
        rec_energy = np.zeros((nrec, 2))
        rec_count = 0
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
            while self.step < stop:
                n_run = stop - self.step
                if self.fluid is not None:
                    if self.step >= self._next_solve:
                        self._fluid_update()
                    n_run = min(n_run, self._next_solve - self.step)
                t_dem = time.perf_counter()
                done, status, self.disp_walls, rec_count = run_steps(
                    n_run, self.step, self.skin, self.disp_walls,
                    self.x, self.y, self.th, self.vx, self.vy, self.om, self.r, self.mass, self.inertia,
                    self.C, self.Cr, self.mat, self.xref, self.yref, self.gx, self.gy,
                    self._perm, self._inv, self._r_p, self._mass_p, self._inertia_p, self._C_p, self._Cr_p,
                    self._mat_p, *self._slots, self._P, self._Fx, self._Fy, self._M,
                    self.finder, self.other, self.hist, self._pos, self._fin_p, self._oth_p, self._hist_p,
                    self._start_p, self._sidx_p, self._wall_p,
                    self._f, self._fn, self._fs, self._slide, self._ovl, self._cpx, self._cpy,
                    self.wpx, self.wpy, self.wex, self.wey, self.wh1, self.wh2, self.wvx, self.wvy,
                    self.wom, self.wcx, self.wcy, self.wmat, self.wall_force,
                    self.phase_start, self.phase_end, self.phase_vx, self.phase_vy, self.phase_om,
                    self.phase_cx, self.phase_cy, self.phase_about_p,
                    self.servo_on, self.servo_start, self.servo_F, self.servo_dx, self.servo_dy,
                    self.servo_G, self.servo_vmax,
                    *self._law_args(),
                    every, rec_count, rec_step, rec_wall, rec_wallpos, self.track_a, self.track_b,
                    rec_track, rec_energy, self._ext, self._has_ext)
                self.dem_s += time.perf_counter() - t_dem
                self.step += done
                if status == BLOWUP:
                    self._store_records(rec_count, rec_step, rec_wall, rec_wallpos, rec_track, rec_energy)
                    bad_step = self.step
                    self._restore_state(good)
                    path = self._save_last_good()
                    raise BlowUpError(
                        f"scene {self.scene.name!r} blew up at step {bad_step}: a contact overlapped more "
                        f"than {MAX_OVERLAP_RATIO:.0%} of a radius, a disc moved more than {MAX_STEP_RATIO:.0%} "
                        f"of its radius in one step, or a force became non-finite. "
                        f"Reduce dt (now {self.dt:.4g}, critical estimate {self.dt_crit:.4g}) or the "
                        f"loading rate. Last good state (step {self.step}) saved to {path}", path)
                if status == REBUILD:
                    self.rebuild()
            if checkpoint is not None and checkpoint_every and self.step - last_ckpt >= checkpoint_every:
                self.save_checkpoint(checkpoint)
                last_ckpt = self.step
        self._store_records(rec_count, rec_step, rec_wall, rec_wallpos, rec_track, rec_energy)
        if checkpoint is not None:
            self.save_checkpoint(checkpoint)
        return self

    def _set_servo_targets(self):
        """Servo targets F_A in effect at the current step (Servo.schedule)."""
        for w, wall in enumerate(self.scene.walls):
            if wall.servo is not None:
                self.servo_F[w] = wall.servo.force_at(self.step)

    def _fluid_update(self):
        """Solve the fluid at the current state (positions x_i, velocities v_{i-1/2}: the half-step
        lag of thesis §3.4) and hold its force, moment and the buoyancy (eq 4.39) for the next
        stride (see :mod:`demflow.coupling`)."""
        f = self.fluid
        out = f.solve(self)
        if not f.setup.moments:
            out[:, 2] = 0.0
        out[:, :2] += self._buoyancy
        self._ext[:] = out
        k = f.stable_stride(self)
        f.strides.append((self.step, k))
        self._next_solve = self.step + k

    def _store_records(self, q, rec_step, rec_wall, rec_wallpos, rec_track, rec_energy):
        if q:
            self.records.append((rec_step[:q].copy(), rec_wall[:q].copy(), rec_wallpos[:q].copy(),
                                  rec_track[:q].copy(), rec_energy[:q].copy()))

    # ------------------------------------------------------------------ snapshots
    def contact_table_arrays(self):
        """Contact forces at the current step, computed without advancing history.

        Returns a dict of arrays for pairs in contact: finder, other, px, py, nx, ny
        (ε, from finder to other), fn, fs, sliding, overlap.
        """
        hist = self.hist.copy()
        m = self.finder.shape[0]
        fx, fy, mi, mj, fn, fs, ovl, cpx, cpy = (np.zeros(m) for _ in range(9))
        slide = np.zeros(m, np.int8)
        contact_forces(self.finder, self.other, hist, self.x, self.y, self.r, self.vx, self.vy, self.om,
                       self.mat, self.n, self.wpx, self.wpy, self.wex, self.wey, self.wh1, self.wh2,
                       self.wvx, self.wvy, self.wom, self.wcx, self.wcy, self.wmat,
                       *self._law_args(), fx, fy, mi, mj, fn, fs, slide, ovl, cpx, cpy, np.inf)
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
    def _copy_state(self):
        return {k: getattr(self, k).copy() for k in _STATE} | {"step": self.step}

    def _restore_state(self, s):
        for k in _STATE:
            setattr(self, k, s[k].copy())
        self.step = s["step"]
        if self.fluid is not None:
            self._next_solve = max(self.step, self.fluid.setup.start)
        self.rebuild()

    def _save_last_good(self):
        out = Path(os.environ.get("DEMFLOW_BLOWUP_DIR", tempfile.gettempdir()))
        path = out / f"{self.scene.name}-last-good-step{self.step}.npz"
        self.save_checkpoint(path)
        return str(path)

    def save_checkpoint(self, path: str | os.PathLike) -> Path:
        """Write the dynamic state to ``path`` (.npz) atomically (temp file + rename)."""
        path = Path(path)
        path.parent.mkdir(parents=True, exist_ok=True)
        data = {k: getattr(self, k) for k in _STATE}
        meta = dict(scene=self.scene.name, step=self.step, n=self.n, nw=self.nw, dt=self.dt)
        fd, tmp = tempfile.mkstemp(dir=path.parent, suffix=".npz.tmp")
        os.close(fd)
        with open(tmp, "wb") as fh:
            np.savez(fh, meta=json.dumps(meta), **data)
        os.replace(tmp, path)
        return path

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
        for k in _STATE:
            if k == "hist":
                continue
            setattr(self, k, getattr(other, k).copy())
        h = np.zeros((other.hist.shape[0], self.n_hist))
        c = min(self.n_hist, other.hist.shape[1])
        h[:, :c] = other.hist[:, :c]  # a stage without shear springs keeps only the normal column
        self.hist = h
        # the discs' forces on the walls as the other stage left them: a saturated stage's first solve
        # hands F_A − F_C to the fluid (thesis §5.3.2) before its first step computes them again
        self.wall_force[:] = other.wall_force
        self.step = 0
        if self.fluid is not None:
            self._next_solve = self.fluid.setup.start
        self.rebuild()
        return self

    def load_checkpoint(self, path: str | os.PathLike) -> "Simulation":
        """Restore a state written by :meth:`save_checkpoint` for the same scene."""
        with np.load(path) as z:
            meta = json.loads(str(z["meta"]))
            if meta["scene"] != self.scene.name or meta["n"] != self.n or meta["nw"] != self.nw:
                raise ValueError(
                    f"checkpoint {path} is for scene {meta['scene']!r} with {meta['n']} discs and "
                    f"{meta['nw']} walls, not {self.scene.name!r} ({self.n}, {self.nw}); build the same scene"
                )
            for k in _STATE:
                setattr(self, k, z[k].copy())
            self.step = int(meta["step"])
        if self.fluid is not None:
            self._next_solve = max(self.step, self.fluid.setup.start)
        self.rebuild()
        return self
