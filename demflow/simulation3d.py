"""A built 3D sphere simulation: structure-of-arrays state plus the compiled cycle.

Created by :func:`demflow.build.build` from a :class:`demflow.scene3d.Scene3D`; never construct it by
hand.  ``run`` advances it (``progress=True`` shows a bar), ``tables`` returns the result tables,
``save_checkpoint``/``load_checkpoint`` make long runs resumable (atomic writes), and a blow-up
raises :class:`demflow.simulation.BlowUpError` with the last good state saved.
"""
from __future__ import annotations

import math
import os
import time
import warnings
import zlib
from pathlib import Path

import numpy as np

from .checkpoint_scene import check_same_scene, last_good_path, read_checkpoint, scene_digest, write_checkpoint
from .contacts.spheres import carry_index, carry_rows, carry_values, sphere_pairs
from .progress import bar as progress_bar
from .scene import EnergyBalanceWarning, SceneError, UnsafeTimeStepWarning, check_whole
from .simulation import ENERGY_ROUND_OFF, BlowUpError
from .state3d import Pairs3, Records3
from .stepping3d import BLOWUP, MAX_OVERLAP_RATIO, MAX_STEP_RATIO, REBUILD, run_steps3
from .tolerances import tol

_STATE = ("pos", "vel", "angvel", "quat", "img")
_BODY_STATE = ("pos", "vel", "L", "angvel", "quat")
_RECORDED = ("step", "plane_force", "plane_pos", "energy", "unbalanced", "contacts", "peak", "track")


class Simulation3D:
    """State and stepping of one 3D sphere scene (see :mod:`demflow.build3d`).

    ``spheres`` (:class:`demflow.state3d.Spheres3`), ``planes``, ``loading``, ``pairs`` (key order,
    with history), the law's compiled parameters ``law_params`` and the ``box``.
    """

    CHUNK = 20000  # steps between last-good-state copies

    def __init__(self, *, scene, spheres, bodies, planes, tris, loading, law, law_params, box, dt, dt_crit, skin,
                 gravity, damping, width, dt_safe=None):
        self.scene = scene
        self.spheres = spheres
        self.bodies = bodies
        self.planes = planes
        self.tris = tris
        self.loading = loading
        self.law = law
        self.law_params = law_params
        self.box = box
        self.dt = float(dt)
        self.dt_crit = float(dt_crit)
        self.dt_safe = float(dt_crit if dt_safe is None else dt_safe)  # integrate.safe_time_step_3d
        self.skin = float(skin)
        self.g = np.asarray(gravity, np.float64)
        self.damping = damping  # Damping3
        self.width = int(width)
        self.step = 0
        self.deepest_overlap = 0.0  # the largest overlap / smaller radius seen at the end of a chunk
        self._overlap_warned = False
        # work of the planes and fixed spheres on the others [0], of damping on recorded steps (<= 0) [1],
        # Newton iterations of an ellipsoid scene [2], energy the contacts dissipated [3]
        self.work = np.zeros(4)
        self.energy_balance = None  # the last evaluation of the energy balance (see _balance_close)
        self._balance = None  # the open balance window: its start (see _balance_open)
        self._balance_key = None  # fingerprint of the state when the window was last carried over
        self.dem_s = 0.0
        self.n_rebuilds = 0
        self._records = []
        self.snapshots = {}
        self.pairs = Pairs3(i=np.empty(0, np.int64), j=np.empty(0, np.int64), hist=np.zeros((0, width)),
                            shift=np.zeros((0, 3)), fn=np.zeros(0), ft=np.zeros((0, 3)), ovl=np.zeros(0),
                            slide=np.zeros(0, np.int8))
        self._scene_digest = scene_digest(self.fixed_parts())  # as built (demflow.checkpoint_scene)
        self.rebuild()

    @property
    def n(self) -> int:
        return self.spheres.pos.shape[0]

    @property
    def n_planes(self) -> int:
        return self.planes.point.shape[0]

    def unwrapped_positions(self) -> np.ndarray:
        """Centres with the periodic image counters undone (continuous trajectories)."""
        out = self.spheres.pos.copy()
        out[:, 0] += self.spheres.img[:, 0] * self.box.lx
        out[:, 1] += self.spheres.img[:, 1] * self.box.ly
        return out

    def rebuild(self):
        """Wrap periodic axes, list neighbours afresh and carry the history over by pair key."""
        sp = self.spheres
        b = self.bodies
        for a, (on, lo, length) in enumerate(((self.box.periodic_x, self.box.x0, self.box.lx),
                                              (self.box.periodic_y, self.box.y0, self.box.ly))):
            if on:
                k = np.floor((sp.pos[:, a] - lo) / length).astype(np.int64)
                # a clump is wrapped by its centre of mass, its members with it
                kb = np.floor((b.pos[:, a] - lo) / length).astype(np.int64)
                member = sp.body >= 0
                k[member] = kb[sp.body[member]]
                b.pos[:, a] -= kb * length
                sp.pos[:, a] -= k * length
                sp.img[:, a] += k
        old = self.pairs
        i, j, shift = sphere_pairs(sp.pos, sp.r, self.skin, self.box, self.planes.point, self.planes.normal,
                                   self.planes.is_mesh, self.tris.v, sp.body, self.tris.imaged,
                                   capacity=old.i.size + old.i.size // 8 + 64)
        # the history, and the last step's forces, overlaps and sliding flags (what a reader of the contacts sees
        # until the next step: a run that ends on a rebuild would otherwise show no contact at all), by pair key
        src = carry_index(old.i, old.j, i, j, self.n + self.n_planes + self.tris.v.shape[0])
        m = i.size
        new = Pairs3(i=i, j=j, hist=np.empty((m, old.hist.shape[1])), shift=shift, fn=np.empty(m),
                     ft=np.empty((m, 3)), ovl=np.empty(m), slide=np.empty(m, np.int8))
        carry_rows(src, old.hist, new.hist)
        carry_values(src, old.fn, new.fn)
        carry_rows(src, old.ft, new.ft)
        carry_values(src, old.ovl, new.ovl)
        carry_values(src, old.slide, new.slide)
        self.pairs = new
        sp.ref[:] = sp.pos
        self.planes.ref[:] = self.planes.point
        self.n_rebuilds += 1

    def _new_records(self, n_steps: int) -> Records3:
        every = int(self.scene.outputs.every)
        nrec = min(n_steps // every + 1, self.CHUNK // every + 1) if every > 0 else 0
        ids = np.asarray(self.scene.outputs.track_spheres, np.int64)
        npl = self.n_planes
        return Records3(every=every, orient=bool(self.scene.outputs.orientation), step=np.zeros(nrec, np.int64), plane_force=np.zeros((nrec, npl, 3)),
                        plane_pos=np.zeros((nrec, npl, 3)), energy=np.zeros((nrec, 5)), unbalanced=np.zeros(nrec),
                        contacts=np.zeros(nrec, np.int64), peak=np.zeros((nrec, 2)), track_ids=ids, track=np.zeros((nrec, ids.size, 6)))

    def run(self, n_steps: int | None = None, *, checkpoint: str | os.PathLike | None = None,
            checkpoint_every: int | None = None, progress: bool | None = None) -> "Simulation3D":
        """Advance ``n_steps`` steps (default: the scene's n_steps minus steps done).

        Records are kept every ``scene.outputs.every`` steps (memory grows with what is recorded,
        chunk by chunk, not with the run length).  With ``checkpoint`` a resumable state is written
        atomically every ``checkpoint_every`` steps and at the end.  A blow-up (an overlap beyond
        half a radius, a step beyond half a radius, a non-finite force) raises BlowUpError after
        saving the last good state.  ``progress``: a bar (True), none (False), or
        :mod:`demflow.progress`'s rule (None: on a terminal, after a few seconds)."""
        if n_steps is None:
            n_steps = max(self.scene.n_steps - self.step, 0)
        self._check_run_length(n_steps)
        if checkpoint_every is not None:
            check_whole("run(checkpoint_every)", checkpoint_every, ge=1)
        with progress_bar(int(n_steps), self.scene.name, show=progress) as bar:
            return self._run(n_steps, checkpoint, checkpoint_every, bar)

    def _run(self, n_steps, checkpoint, checkpoint_every, bar) -> "Simulation3D":
        target = self.step + int(n_steps)
        snaps = sorted(s for s in self.scene.outputs.snapshots if self.step <= s <= target)
        last_ckpt = self.step
        if self._balance is None or self._balance_key != self._fingerprint():
            self._balance = None  # a new run, or the state was changed between runs: a new window
        while True:
            while snaps and snaps[0] == self.step:
                self.snapshot_now()
                snaps.pop(0)
            if self.step >= target:
                break
            stop = min(target, snaps[0] if snaps else target, self.step + self.CHUNK)
            good = self._copy_state()
            if self._balance is None:
                self._balance = self._balance_open()
            rec = self._new_records(stop - self.step)
            rec_count = 0
            while self.step < stop:
                t0 = time.perf_counter()
                done, status, rec_count = self._advance(stop - self.step, rec, rec_count)
                self.dem_s += time.perf_counter() - t0
                self.step += done
                bar.update(done)
                # the cycle's tests see overlaps, steps and forces; one O(n) pass per call of the cycle sees a
                # NaN or inf they did not (a moment, a spin, a plane driven to infinity, a free body under a NaN
                # gravity)
                nonfinite = self._nonfinite_state()
                if status == BLOWUP or nonfinite is not None:
                    self._keep_records(rec, rec_count)
                    bad = self.step
                    self._restore_state(good)
                    path = self._save_last_good()
                    why = (f"{nonfinite} is not finite (its origin may be gravity (now {tuple(map(float, self.g))}), "
                           "a mass, a contact law or a wall's motion); check those for NaN or infinite values, "
                           "then reduce" if nonfinite is not None else
                           f"a contact overlapped more than {MAX_OVERLAP_RATIO:.0%} of a radius, a sphere moved "
                           f"more than {MAX_STEP_RATIO:.0%} of its radius in one step, or a force became "
                           "non-finite. Reduce")
                    raise BlowUpError(
                        f"scene {self.scene.name!r} blew up at step {bad}: {why} dt (now {self.dt:.4g}, critical "
                        f"estimate {self.dt_crit:.4g}, safe estimate {self.dt_safe:.4g}) or the loading rate. Last good state (step {self.step}) "
                        f"saved to {path}", path)
                if status == REBUILD:
                    self.rebuild()
            why = self._balance_close(self._balance)
            if why and self.scene.energy_check == "warn":
                warnings.warn(f"scene {self.scene.name!r}: {why} (energy_check='warn': the run goes on)",
                              EnergyBalanceWarning, stacklevel=3)
            elif why:
                self._keep_records(rec, rec_count)
                self._balance = None
                self._restore_state(good)
                path = self._save_last_good()
                raise BlowUpError(f"scene {self.scene.name!r} blew up between steps {good['step']} and the check at "
                                  f"step {self.energy_balance['end']}: {why}. Last good state (step {self.step}) "
                                  f"saved to {path}", path)
            if why or self.step - self._balance["step"] >= self.CHUNK:
                self._balance = dict(self._balance["end_state"], step=self.step)  # the next window starts here
            self._keep_records(rec, rec_count)
            self._check_overlap_coverage()
            if checkpoint is not None and checkpoint_every and self.step - last_ckpt >= checkpoint_every:
                self.save_checkpoint(checkpoint)
                last_ckpt = self.step
        if checkpoint is not None:
            self.save_checkpoint(checkpoint)
        self._balance_key = self._fingerprint()
        return self

    def deepest_overlap_now(self) -> float:
        """The largest overlap of a listed pair at the last force evaluation, as a fraction of the smaller
        radius (a wall's: the sphere's; a gap is negative); 0 when nothing is listed."""
        return self._deepest_relative_to(self.spheres.r)

    def _deepest_relative_to(self, r: np.ndarray) -> float:
        """The largest listed overlap over the smaller of the pair's lengths ``r`` (a wall's: the particle's)."""
        pr = self.pairs
        if pr.ovl.size == 0:
            return 0.0
        n = self.n
        rmin = np.where(pr.j < n, np.minimum(r[pr.i], r[np.minimum(pr.j, n - 1)]), r[pr.i])
        return float(np.max(pr.ovl / rmin))

    def _check_overlap_coverage(self) -> None:
        """Warn (once) when Hertz contacts have gone deeper than the scene's ``max_overlap`` so far that the
        time step is above the safe estimate at that depth.  The estimate was taken at ``max_overlap``
        (:func:`demflow.integrate.safe_time_step_3d`); every Hertzian spring and dashpot scales as √δ and
        √(m k), so the safe step at overlap δ is dt_safe × (max_overlap/δ)^¼.  Above it nothing stops an
        unstable run may go on until the energy balance (:meth:`_balance_close`) sees it.  (Measured before that
        balance existed: the KE of the face-centred cubic test packing at 1.05× its measured critical step grew
        6.6e12-fold with overlaps below 1.5 % of the radius, and no test fired.)"""
        from .laws.hertz_mindlin import HertzMindlin

        if not isinstance(self.law, HertzMindlin) or self.pairs.ovl.size == 0:
            return
        deepest = self.deepest_overlap_now()
        self.deepest_overlap = max(self.deepest_overlap, deepest)
        declared = float(self.scene.max_overlap)
        if self._overlap_warned or self.scene.allow_supercritical or deepest <= declared or self.dt > self.dt_safe:
            return  # (a dt above the estimate at max_overlap was accepted, with a warning, by build)
        safe_here = self.dt_safe * (declared / deepest) ** 0.25
        if self.dt > safe_here:
            self._overlap_warned = True
            warnings.warn(
                f"scene {self.scene.name!r}: at step {self.step} a contact overlaps {deepest:.4g} of the smaller radius, "
                f"deeper than scene.max_overlap={declared:g}; at that depth the safe critical time step is "
                f"{safe_here:.4g}, below dt={self.dt:.4g}: the run may be unstable (the energy balance stops a "
                f"growing one). Declare scene.max_overlap >= {deepest:.4g} (build then gives the step for it) or "
                "reduce dt", UnsafeTimeStepWarning, stacklevel=4)

    # ------------------------------------------------------------------ energy balance
    def _fingerprint(self) -> int:
        """A checksum of the dynamic state: a window of the energy balance carries over to the next run
        only when nothing changed the state in between."""
        h = 0
        for a in self._state_arrays().values():
            h = zlib.crc32(np.ascontiguousarray(a).view(np.uint8), h)
        return h

    def _probe_energy(self) -> dict | None:
        """The energy of the current state (step n), from one step of the compiled cycle run on a copy of the
        state (nothing of this simulation changes): kinetic as the product of the half-step velocities
        either side of step n (see below), elastic of the contacts at x_n as a recorded step computes it
        (the law's :func:`~demflow.laws.base.law_energy3`), the unwrapped centres of the bodies gravity moves (free
        spheres and clumps; fixed spheres are moved by whoever prescribes them) with their masses, and
        the running accounts (work of the planes and fixed spheres, energy the contacts dissipated) with
        what the probe step adds to them (the energy at step n includes the contacts' increments of step n:
        the accounts of a window from n0 to n1 are the steps' n0 + 1 .. n1).  None when that step cannot be
        taken (a blow-up the cycle's own tests report)."""
        def dup(t):
            return type(t)(*[np.array(a, copy=True) if isinstance(a, np.ndarray) else a for a in t])

        keep = self.spheres, self.bodies, self.pairs, self.planes, self.tris, self.damping, self.work
        ell = getattr(self, "ell", None)
        npl = self.n_planes
        rec = Records3(every=1, orient=False, step=np.zeros(1, np.int64), plane_force=np.zeros((1, npl, 3)),
                       plane_pos=np.zeros((1, npl, 3)), energy=np.zeros((1, 5)), unbalanced=np.zeros(1),
                       contacts=np.zeros(1, np.int64), peak=np.zeros((1, 2)), track_ids=np.zeros(0, np.int64),
                       track=np.zeros((1, 0, 6)))
        copies = [dup(t) for t in keep[:6]]
        work = keep[6].copy()
        try:
            self.spheres, self.bodies, self.pairs, self.planes, self.tris, self.damping = copies
            self.work = work
            if ell is not None:
                self.ell = dup(ell)
            _, _, count = self._advance(1, rec, 0)
        finally:
            self.spheres, self.bodies, self.pairs, self.planes, self.tris, self.damping, self.work = keep
            if ell is not None:
                self.ell = ell
        if count != 1:
            return None
        sp, b = self.spheres, self.bodies
        sp1, b1 = copies[0], copies[1]
        # kinetic energy as ½ m v_{n-1/2}·v_{n+1/2} (and ½ ω_{n-1/2}·I ω_{n+1/2}; a clump's ¼(ω₀·L₁ + ω₁·L₀)):
        # its change over a step is exactly the mean force of the step's two ends times the displacement, so
        # that a stable linear contact and gravity close to round-off, whatever Δt (the on-step form
        # ½ m ((v_{n-1/2} + v_{n+1/2})/2)² oscillates by O((ωΔt)²) of the energy exchanged)
        own = sp.fixed != 2
        kin = float(0.5 * np.sum(sp.mass[own] * np.sum(sp.vel[own] * sp1.vel[own], axis=1))
                    + 0.5 * np.sum(sp.inertia[own] * np.sum(sp.angvel[own] * sp1.angvel[own], axis=1)))
        if b.pos.shape[0]:
            kin += float(0.5 * np.sum(b.mass * np.sum(b.vel * b1.vel, axis=1))
                         + 0.25 * np.sum(b.angvel * b1.L + b1.angvel * b.L))
        pos = self.unwrapped_positions()
        free = sp.fixed == 0
        bpos = b.pos.copy()
        if bpos.shape[0]:  # a clump's members carry its periodic image counter
            first = b.start[:-1]
            bpos[:, 0] += sp.img[first, 0] * self.box.lx
            bpos[:, 1] += sp.img[first, 1] * self.box.ly
        e = rec.energy[0]
        return dict(energy=kin + float(e[2]), kinetic=kin, elastic=float(e[2]),
                    pos=pos[free], mass=sp.mass[free].copy(), bpos=bpos, bmass=b.mass.copy(),
                    work=float(work[0]), damping=float(work[1]), dissipated=float(work[3]))

    def mechanical_energy(self) -> dict:
        """The energy of the current state as the energy balance counts it (:meth:`_probe_energy`, nothing
        changes): ``kinetic`` (½ m v_{n-1/2}·v_{n+1/2}, rotations included), ``elastic`` (the contacts'
        springs at x_n) [force·length]; NaN when the probe step cannot be taken."""
        e = self._probe_energy()
        if e is None:
            return dict(kinetic=math.nan, elastic=math.nan)
        return dict(kinetic=e["kinetic"], elastic=e["elastic"])

    def _balance_open(self) -> dict | None:
        """Open a window of the energy balance at the current step."""
        return dict(step=self.step, start=self._probe_energy())

    def _balance_close(self, b: dict) -> str | None:
        """Check the window ``b`` up to now (issue 17 item 4, in 3D; the 2D balance is
        :meth:`demflow.simulation.Simulation._balance_close`):

            created = Δ(kinetic + elastic) + dissipated by the contacts (dashpots, Coulomb slip)
                      - work of the planes and fixed spheres - work of gravity - work of the damping.

        A stable run creates nothing but round-off and O(Δt) discretisation; an unstable step creates
        energy, and friction can dissipate it as fast as it grows, so that overlaps stay small.  The work of
        global, local and adaptive damping (≤ 0) is the running sum the steps keep (``work[1]``, the records'
        ``damping_work``), so that a damped run's balance closes as an undamped one's.  Returns why
        the window blew up, or None; keeps the numbers in ``energy_balance`` (and the end state in
        ``b['end_state']``, the start of the next window)."""
        end = self._probe_energy()
        b["end_state"] = dict(start=end)
        start = b["start"]
        if start is None or end is None or self.step == b["step"]:
            return None
        g = self.g
        gravity = float(np.sum(start["mass"] * ((end["pos"] - start["pos"]) @ g))
                        + np.sum(start["bmass"] * ((end["bpos"] - start["bpos"]) @ g)))
        walls = end["work"] - start["work"]
        contacts = end["dissipated"] - start["dissipated"]
        damping = end["damping"] - start["damping"]
        e0, e1 = start["energy"], end["energy"]
        created = (e1 - e0) + contacts - walls - gravity - damping
        supplied = abs(e0) + abs(walls) + abs(gravity)
        self.energy_balance = dict(start=b["step"], end=self.step, energy_start=e0, energy_end=e1,
                                   kinetic_end=end["kinetic"], elastic_end=end["elastic"],
                                   dissipated_contacts=contacts, work_walls=walls, work_gravity=gravity,
                                   work_damping=damping, created=created, supplied=supplied,
                                   ratio=created / supplied if supplied > 0 else math.inf)
        limit = tol("energy.blow-up-3d").value
        if math.isfinite(created) and (created <= limit * supplied
                                       or created <= ENERGY_ROUND_OFF * (abs(e1) + abs(contacts) + abs(damping))):
            return None
        return (f"the energy balance of steps {b['step']}-{self.step} does not close: the steps created {created:.6g} "
                f"(Δ(kinetic + elastic) {e1 - e0:.6g} + dissipated by the contacts {contacts:.6g} - work of planes and "
                f"fixed spheres {walls:.6g} - work of gravity {gravity:.6g} - work of the damping {damping:.6g}), more "
                f"than {limit:g} × the {supplied:.6g} "
                f"the window started with or was given (tolerance 'energy.blow-up-3d', demflow/tolerances.py): the "
                f"time step is unstable. Reduce dt (now {self.dt:.4g}, safe estimate {self.dt_safe:.4g}, "
                "demflow.integrate.safe_time_step_3d; for Hertz contacts deeper than scene.max_overlap the "
                "estimate is not safe: declare the overlap they reach)")

    def _nonfinite_state(self) -> str | None:
        """The first non-finite quantity of the particles, bodies, planes, meshes or contact history, or None."""
        from .simulation import first_nonfinite

        sp, b, pl = self.spheres, self.bodies, self.planes
        return first_nonfinite({
            **{f"spheres.{k}": getattr(sp, k) for k in ("pos", "vel", "angvel", "quat", "FM")},
            **{f"bodies.{k}": getattr(b, k) for k in ("pos", "vel", "L", "angvel", "quat")},
            **{f"planes.{k}": getattr(pl, k) for k in ("point", "vel", "force")},
            "meshes.vertices": self.tris.v, "pairs.hist": self.pairs.hist})

    def _advance(self, n_steps: int, rec: Records3, rec_count: int):
        """One call of the compiled cycle: (steps done, status, records written)."""
        return run_steps3(n_steps, self.step, self.skin, self.spheres, self.bodies, self.pairs, self.planes,
                          self.tris, self.loading, self.law_params, self.g, self.damping, self.dt, rec, rec_count,
                          self.work)

    def _check_run_length(self, n_steps) -> None:
        """Refuse up front a run whose records would not fit in memory (they grow with what is recorded,
        chunk by chunk, not with n_steps), with the numbers."""
        from .scene import MAX_WHOLE, check_whole
        from .simulation import SNAPSHOT_BYTES_PER_DISC, memory_limit, recorded_steps

        check_whole("run(n_steps)", n_steps, le=MAX_WHOLE - self.step)
        every = int(self.scene.outputs.every)
        per = 8 * (2 + 6 * self.n_planes + 5 + 1 + 1 + 2 + 6 * len(self.scene.outputs.track_spheres))
        rows = recorded_steps(self.step, int(n_steps), every)
        snaps = sum(1 for st in self.scene.outputs.snapshots if self.step <= st <= self.step + int(n_steps))
        need = rows * per + snaps * self.n * SNAPSHOT_BYTES_PER_DISC
        limit = memory_limit()
        if need > limit:
            raise SceneError(f"run(n_steps={n_steps}) would record {rows} rows of {per} bytes and {snaps} snapshots: "
                             f"{need / 2 ** 30:.3g} GiB, over the {limit / 2 ** 30:.3g} GiB a run may hold (half of this "
                             "machine's memory; DEMFLOW_MEMORY_LIMIT overrides it); record less often "
                             "(scene.outputs.every) or shorten the run")

    def _keep_records(self, rec: Records3, count: int) -> None:
        if count:
            self._records.append({k: getattr(rec, k)[:count].copy() for k in
                                  _RECORDED})

    def records(self) -> dict:
        """Everything recorded so far, concatenated: step, plane_force (R, np, 3), plane_pos,
        energy (R, 5: kinetic translation, kinetic rotation, elastic, potential, damping work),
        contacts (R,), peak (R, 2: largest normal force, largest overlap), track (R, nt, 6)."""
        if not self._records:
            rec = self._new_records(0)
            return {k: getattr(rec, k)[:0] for k in _RECORDED}
        return {k: np.concatenate([r[k] for r in self._records]) for k in self._records[0]}

    def snapshot_now(self) -> None:
        """Keep the spheres' state and the touching contacts at the current step (see :meth:`tables`)."""
        self.snapshots[self.step] = self.tables(include_records=False)

    # a scene of clumps has a clumps table, and its members' rows carry their clump's orientation (ellipsoids: no)
    _clump_table = True

    def tables(self, include_records: bool = True) -> dict:
        """The result tables (pandas): ``spheres`` (state now), ``contacts`` (touching pairs now,
        force on i), ``planes`` and, with ``include_records``, ``records`` (one row per recorded step).

        A scene with clumps also has ``clumps`` (one row per clump: id, centre of mass x, y, z (periodic
        images undone), velocity, angular velocity (world frame), orientation q (body frame -> world), mass,
        principal moments I1..I3 [mass·length²], members), and its ``spheres`` rows of members carry ``clump``
        (the clump's id; -1 for a sphere of its own), the clump's orientation and ``mass`` NaN: a member has
        no mass of its own (the clump's mass is in ``clumps``; Σ spheres.mass over free spheres + Σ
        clumps.mass is the scene's mass)."""
        import pandas as pd

        sp = self.spheres
        pos = self.unwrapped_positions()
        b = self.bodies
        clumps = self._clump_table and b.pos.shape[0] > 0
        quat = sp.quat
        mass = sp.mass
        if clumps:
            member = sp.body >= 0
            quat = sp.quat.copy()
            quat[member] = b.quat[sp.body[member]]
            mass = np.where(member, np.nan, sp.mass)
        spheres = pd.DataFrame({"id": np.arange(self.n), "x": pos[:, 0], "y": pos[:, 1], "z": pos[:, 2],
                                "vx": sp.vel[:, 0], "vy": sp.vel[:, 1], "vz": sp.vel[:, 2],
                                "wx": sp.angvel[:, 0], "wy": sp.angvel[:, 1], "wz": sp.angvel[:, 2],
                                "qw": quat[:, 0], "qx": quat[:, 1], "qy": quat[:, 2], "qz": quat[:, 3],
                                "r": sp.r, "mass": mass})
        if clumps:
            spheres["clump"] = sp.body.copy()
        p = self.pairs
        on = p.ovl > 0
        contacts = pd.DataFrame({"i": p.i[on], "j": p.j[on], "wall": p.j[on] >= self.n, "fn": p.fn[on],
                                 "ftx": p.ft[on, 0], "fty": p.ft[on, 1], "ftz": p.ft[on, 2],
                                 "overlap": p.ovl[on], "sliding": p.slide[on].astype(bool)})
        names = [pl.name for pl in self.scene.planes] + [mh.name for mh in self.scene.meshes]
        planes = pd.DataFrame({"name": names, "px": self.planes.point[:, 0], "py": self.planes.point[:, 1],
                               "pz": self.planes.point[:, 2], "fx": self.planes.force[:, 0],
                               "fy": self.planes.force[:, 1], "fz": self.planes.force[:, 2]})
        out = {"spheres": spheres, "contacts": contacts, "planes": planes}
        if clumps:
            img = sp.img[b.start[:-1]]  # a clump is wrapped with its members (rebuild)
            cx = b.pos[:, 0] + img[:, 0] * self.box.lx
            cy = b.pos[:, 1] + img[:, 1] * self.box.ly
            out["clumps"] = pd.DataFrame({
                "id": np.arange(b.pos.shape[0]), "x": cx, "y": cy, "z": b.pos[:, 2].copy(),
                "vx": b.vel[:, 0], "vy": b.vel[:, 1], "vz": b.vel[:, 2],
                "wx": b.angvel[:, 0], "wy": b.angvel[:, 1], "wz": b.angvel[:, 2],
                "qw": b.quat[:, 0], "qx": b.quat[:, 1], "qy": b.quat[:, 2], "qz": b.quat[:, 3],
                "mass": b.mass, "I1": b.moments[:, 0], "I2": b.moments[:, 1], "I3": b.moments[:, 2],
                "members": np.diff(b.start)})
        if include_records:
            r = self.records()
            cols = {"step": r["step"], "t": r["step"] * self.dt, "contacts": r["contacts"],
                    "kinetic_translation": r["energy"][:, 0], "kinetic_rotation": r["energy"][:, 1],
                    "elastic": r["energy"][:, 2], "potential": r["energy"][:, 3], "damping_work": r["energy"][:, 4],
                    "fn_max": r["peak"][:, 0], "overlap_max": r["peak"][:, 1], "unbalanced": r["unbalanced"]}
            for q, name in enumerate(names):
                for a, ax in enumerate("xyz"):
                    cols[f"{name}_f{ax}"] = r["plane_force"][:, q, a]
                    cols[f"{name}_p{ax}"] = r["plane_pos"][:, q, a]
            for t, i in enumerate(self.scene.outputs.track_spheres):
                for a, ax in enumerate(("x", "y", "z", "vx", "vy", "vz")):
                    cols[f"s{i}_{ax}"] = r["track"][:, t, a]
            out["records"] = pd.DataFrame(cols)
        return out

    # ------------------------------------------------------------------ state I/O
    def _state_arrays(self) -> dict:
        out = {k: getattr(self.spheres, k) for k in _STATE}
        out.update({f"body_{k}": getattr(self.bodies, k) for k in _BODY_STATE})
        out.update(alpha_now=self.damping.alpha_now, prev_r=self.damping.prev_r, prev_dx=self.damping.prev_dx,
                   plane_point=self.planes.point, tri_v=self.tris.v, plane_vel=self.planes.vel, plane_force=self.planes.force,
                   pair_i=self.pairs.i, pair_j=self.pairs.j, hist=self.pairs.hist, work=self.work,
                   pair_fn=self.pairs.fn, pair_ft=self.pairs.ft, pair_ovl=self.pairs.ovl, pair_slide=self.pairs.slide,
                   pair_shift=self.pairs.shift, ref=self.spheres.ref, plane_ref=self.planes.ref)
        return out

    def _set_state(self, s: dict) -> None:
        for k in _STATE:
            getattr(self.spheres, k)[:] = s[k]
        for k in _BODY_STATE:
            getattr(self.bodies, k)[:] = s[f"body_{k}"]
        for k in ("alpha_now", "prev_r", "prev_dx"):
            getattr(self.damping, k)[:] = s[k]
        self.planes.point[:] = s["plane_point"]
        self.tris.v[:] = s["tri_v"]
        self.planes.vel[:] = s["plane_vel"]
        self.planes.force[:] = s["plane_force"]
        w = np.asarray(s["work"], np.float64)
        self.work[:] = 0.0
        self.work[:w.shape[0]] = w  # a checkpoint of an older demflow keeps fewer accounts
        w = self.width
        m = np.asarray(s["pair_i"]).size
        # the last step's pair outputs (a checkpoint of an older demflow has none: zero until the next step)
        self.pairs = self.pairs._replace(i=np.array(s["pair_i"], np.int64), j=np.array(s["pair_j"], np.int64),
                                         hist=np.array(s["hist"], np.float64).reshape(-1, w),
                                         fn=np.array(s["pair_fn"], np.float64) if "pair_fn" in s else np.zeros(m),
                                         ft=np.array(s["pair_ft"], np.float64).reshape(-1, 3) if "pair_ft" in s
                                         else np.zeros((m, 3)),
                                         ovl=np.array(s["pair_ovl"], np.float64) if "pair_ovl" in s else np.zeros(m),
                                         slide=np.array(s["pair_slide"], np.int8) if "pair_slide" in s
                                         else np.zeros(m, np.int8))
        if all(k in s for k in ("pair_shift", "ref", "plane_ref")):
            # the pair list as it was, with its image shifts and the positions of its build: the run goes on
            # with the same list, the same rebuild steps and the same periodic wraps as one never stopped (a
            # rebuild here would wrap and re-list at another step than the uninterrupted run: other bits)
            self.pairs = self.pairs._replace(shift=np.array(s["pair_shift"], np.float64).reshape(-1, 3))
            self.spheres.ref[:] = s["ref"]
            self.planes.ref[:] = s["plane_ref"]
        else:  # a checkpoint of an older demflow: list afresh
            self.rebuild()

    def _copy_state(self):
        return {k: np.array(v, copy=True) for k, v in self._state_arrays().items()} | {"step": self.step}

    def _restore_state(self, s):
        self.step = s["step"]
        self._set_state(s)

    def _save_last_good(self):
        path = last_good_path(self.scene.name, self.step)
        self.save_checkpoint(path)
        return str(path)

    def fixed_parts(self) -> dict:
        """What the scene fixes and a run does not change, by name (:mod:`demflow.checkpoint_scene`): a checkpoint
        continues only a simulation where these are the same."""
        sp, b, pl, dm = self.spheres, self.bodies, self.planes, self.damping
        return {"particles (radius, mass, inertia, material, fixed, body)": (sp.r, sp.mass, sp.inertia, sp.mat,
                                                                             sp.fixed, sp.body),
                "clumps (mass, moments, members)": (b.mass, b.moments, b.start, b.offset),
                "walls (normals, materials, meshes)": (pl.normal, pl.mat, pl.is_mesh, self.tris.wall, self.tris.imaged),
                "time step": self.dt, "gravity": self.g, "contact law": self.law_params, "box": self.box,
                "damping": (dm.alpha, dm.c_abs, dm.c_rot_abs, dm.local, dm.adaptive)}

    def save_checkpoint(self, path: str | os.PathLike) -> Path:
        """Write the dynamic state to ``path`` (.npz) atomically (temp file + rename)."""
        meta = dict(scene=self.scene.name, step=self.step, n=self.n, n_planes=self.n_planes, dt=self.dt, dim=3,
                    static=self._scene_digest)
        return write_checkpoint(Path(path), meta, self._state_arrays())

    def load_checkpoint(self, path: str | os.PathLike) -> "Simulation3D":
        """Restore a state written by :meth:`save_checkpoint` for the same scene."""
        meta, state = read_checkpoint(path)
        if meta.get("dim") != 3 or meta["scene"] != self.scene.name or meta["n"] != self.n \
                or meta["n_planes"] != self.n_planes:
            raise ValueError(
                f"checkpoint {path} is for scene {meta['scene']!r} ({meta['n']} spheres, "
                f"{meta.get('n_planes')} planes), not {self.scene.name!r} ({self.n}, {self.n_planes}); "
                "build the same scene")
        check_same_scene(path, meta, self._scene_digest)
        self.step = int(meta["step"])
        self._set_state(state)
        return self
