"""Public solver API: fold a :class:`~.mesh.FoldMesh` to equilibrium with Origami Simulator's model.

Methods (all minimise/settle the same energy, ``core.solve.forces``):

* ``"fast"`` — damped Gauss–Newton with a numpy-only sparse Cholesky (nested dissection, ``core.solve.newton``);
* ``"faithful"`` — Origami Simulator's explicit damped dynamics (``core.solve.faithful``), run until the residual
  criterion holds or the step/time cap is hit;
* ``"isometric"`` — the fast solver with bars ``isometric_factor`` (1000×) stiffer, so the sheet barely stretches.

Convergence, shared by every method, is scale-free: the model is normalised to a unit bounding sphere and the
residual is ``max_i |F_i|`` divided by a hinge force scale (``forces.characteristic_force``); it is reported with
the iteration count. Positions come back in the mesh's millimetres.
"""

from __future__ import annotations

import math
import time
from collections.abc import Generator
from dataclasses import dataclass, field, replace

import numpy as np

from .. import as_units, run_to_end
from ..mesh.fold_mesh import FoldMesh
from ..pattern.model import PatternError
from . import path
from .constraints import GLUE_STIFFNESS, Constraints, rigid_fit
from .dissection import NestedDissection, dissect_pairs_steps
from .faithful import SolverError, faithful_solve, time_step
from .forces import characteristic_force, evaluate
from .linalg import single_threaded_blas
from .model import BarHingeModel, build_model, with_glue
from .newton import TAIL_RESIDUAL, Fixed, HessianAssembler, inertia_shift, newton_steps
from .pose import on_table, resting_pieces

METHODS = ("fast", "faithful", "isometric")

__all__ = ["METHODS", "FoldResult", "SolverError", "SolverSettings", "Solver", "rigid_rms", "solve"]


@dataclass
class SolverSettings:
    """Material and solver settings; defaults are Origami Simulator's (reference §3.1).

    ``tolerance`` is the scale-free residual (max nodal force ÷ hinge force scale). ``max_iterations`` caps Newton
    iterations (of a whole continuation; 1000: a clef rolling up at a 1 mm interval needs 217, at 0.5 mm 380, and
    the path is long, not stuck — docs/solver.md, "One natural state"; a designer's crumpling curved Miura grids
    and a four-turn spiral at 180° need 501–1,075); ``max_steps`` and ``time_limit``
    (seconds, ``None`` = no limit) cap the faithful integrator.
    A fast solve from the flat sheet folds by continuation: fold percent steps of at most ``continuation_step``,
    each warm-started from the last (intermediate steps solved to ``continuation_tolerance``, the last to
    ``tolerance``). ``exact_tail`` lets the Newton solver use the exact Hessian near equilibrium
    (``core.solve.newton``).
    """

    axial_stiffness: float = 20.0
    crease_stiffness: float = 0.7
    panel_stiffness: float = 0.7
    face_stiffness: float = 0.2
    damping: float = 0.45
    tolerance: float = 1e-6
    max_iterations: int = 1000
    max_steps: int = 200_000
    time_limit: float | None = None
    isometric: bool = False
    isometric_factor: float = 1000.0
    continuation_step: float = 0.25
    continuation_tolerance: float = 1e-3
    exact_tail: bool = True
    dt_rule: str = "all_terms"
    dt_safety: float = 0.9
    check_every: int = 100

    def effective_axial(self) -> float:
        return self.axial_stiffness * (self.isometric_factor if self.isometric else 1.0)


@dataclass
class FoldResult:
    """Outcome of one solve. ``positions`` ``(n, 3)`` mm; ``fold_angles`` ``(e,)`` simulated degrees per mesh edge
    (``nan`` on edges with fewer than two triangles); ``energy`` in normalised units; ``residual`` scale-free.

    ``force_evaluations`` counts every evaluation of the model (gradient or energy-only, line search included);
    ``hessian_assemblies`` (assembly + block factorisation) and ``linear_solves`` (applications of a factorisation)
    are reported separately (0 for the faithful solver).
    ``exact_iterations`` counts Newton steps with the exact Hessian, ``saddle_escapes`` negative-curvature steps out
    of a saddle (at fold percents ``saddle_percents``); ``continuation_steps`` is the number of fold-percent steps
    of a continuation from the flat sheet (0 for a single solve); ``negative_pivots`` is the number of negative
    eigenvalues of the exact Hessian at the state reached, when measured (0: a stable minimum).
    """

    positions: np.ndarray
    fold_angles: np.ndarray
    iterations: int
    force_evaluations: int
    converged: bool
    residual: float
    energy: float
    simulation_ms: float
    message: str
    method: str
    simulation_cpu_ms: float = math.nan
    """CPU time of the process during the solve (``time.process_time``), beside the wall time ``simulation_ms``:
    on a shared machine wall time was 2–4× it (a designer session: 24.8 s wall for 13.3 s CPU)."""
    hessian_assemblies: int = 0
    linear_solves: int = 0
    theta: np.ndarray = field(default_factory=lambda: np.zeros(0))
    velocities: np.ndarray | None = None
    dt: float | None = None
    exact_iterations: int = 0
    saddle_escapes: int = 0
    continuation_steps: int = 0
    negative_pivots: int | None = None
    saddle_percents: list[float] = field(default_factory=list)
    reused_iterations: int = 0
    """Iterations of the natural path's grid states taken from the solver's kept ones (counted in ``iterations``,
    not run again by this solve)."""

    @property
    def ms(self) -> float:
        return self.simulation_ms


@dataclass
class SolveProgress:
    """One step of a sliced solve (:meth:`Solver.solve_steps`): iteration, residual, positions (mm) reached."""

    iteration: int
    residual: float
    positions: np.ndarray


class Solver:
    """A model plus its reusable solver data (Hessian ordering, time step) for repeated solves of one mesh.

    The animation and the pipeline keep one of these so the per-mesh preprocessing is paid once.
    """

    def __init__(
        self,
        mesh: FoldMesh,
        settings: SolverSettings | None = None,
        method: str = "fast",
        constraints: Constraints | None = None,
    ):
        if method not in METHODS:
            raise ValueError(f"unknown solver method {method!r}; choose one of {', '.join(METHODS)}")
        if constraints is not None and constraints.empty:
            constraints = None
        if constraints is not None:
            if method == "faithful":
                raise PatternError("pins and glue need the fast or isometric solver, not the faithful one")
            constraints.check(mesh.n_vertices)
        settings = settings or SolverSettings()
        if method == "isometric":
            settings = replace(settings, isometric=True)
        self.mesh = mesh
        self.method = method
        self.settings = settings
        self.model: BarHingeModel = build_model(
            mesh,
            axial_stiffness=settings.effective_axial(),
            crease_stiffness=settings.crease_stiffness,
            panel_stiffness=settings.panel_stiffness,
            face_stiffness=settings.face_stiffness,
            damping=settings.damping,
        )
        self.constraints = constraints
        if constraints is not None:  # glue: zero-length bars after the mesh's (core.solve.constraints)
            self.model = with_glue(self.model, constraints.glue, GLUE_STIFFNESS, settings.damping)
        self.force_scale = characteristic_force(self.model, settings.crease_stiffness, settings.panel_stiffness)
        self._assembler: HessianAssembler | None = None
        self._dt: float | None = None
        self.lm_lambda = 1e-3
        self._path_key: tuple[str, int] | None = None  # the settings and pins the kept path states belong to
        self._path_states: dict[float, path.PathState] = {}
        self._resting: list[tuple[np.ndarray | None, np.ndarray]] | None = None

    def _placed(self, positions: np.ndarray) -> np.ndarray:
        """``positions`` (mm) with the sheet's centre face on the table (:mod:`.pose`), or, with pins, turned about
        them as the face asks where they leave a turn free: the placement of a fast solve's result is then a
        function of its shape (and pins) alone, not of the path to it."""
        if self._resting is None:
            glued = self.constraints is not None and len(self.constraints.glue) > 0
            self._resting = resting_pieces(self.mesh, together=glued)
        pins = None if self.constraints is None else self.constraints.pins  # they place it; the face what they leave
        return on_table(positions, self.mesh.vertices_3d, self._resting, pins)

    def _placed_steps(self, steps: Generator[SolveProgress, None, FoldResult]):
        """``steps`` with every position shown and the result :meth:`_placed` (a live display does not jump)."""
        while True:
            try:
                progress = next(steps)
            except StopIteration as done:
                r = done.value
                r.positions = self._placed(r.positions)
                return r
            yield SolveProgress(progress.iteration, progress.residual, self._placed(progress.positions))

    @property
    def assembler(self) -> HessianAssembler:
        """The Hessian's storage and factorisation (nested-dissection ordering, scatter indices), made once."""
        return run_to_end(self.prepare_steps())

    def prepare_steps(self) -> Generator[str, None, HessianAssembler]:
        """Make :attr:`assembler` in units for a Blender job: the nested dissection of the coupling graph one
        component at a time ("ordering": ~95 ms in all at 3,000 faces, ~220 ms on a 4,000-face clef of many
        strips), then the factorisation's structure ("structure", ~35 ms), then the scatter indices ("scatter",
        :data:`.newton.SCATTER_UNIT` block pairs per unit); returns the assembler (at once if it exists)."""
        if self._assembler is None:
            pairs = HessianAssembler.coupling_pairs(self.model)
            dissection = yield from as_units(dissect_pairs_steps(self.model.n_nodes, pairs), "ordering")
            matrix = NestedDissection(self.model.n_nodes, pairs, dissection=dissection)
            yield "structure"
            self._assembler = yield from HessianAssembler.steps(self.model, matrix)
        return self._assembler

    @property
    def dt(self) -> float:
        if self._dt is None:
            s = self.settings
            self._dt = time_step(self.model, s.dt_rule, s.dt_safety, s.effective_axial())
        return self._dt

    def edge_angles(self, theta: np.ndarray) -> np.ndarray:
        """Per-mesh-edge fold angles in degrees from per-hinge θ (``nan`` where there is no hinge)."""
        out = np.full(self.model.n_edges, np.nan)
        out[self.model.hinge_edge] = np.rad2deg(theta)
        return out

    def start_angles(self, x: np.ndarray, percent: float) -> np.ndarray:
        """Fold angles (rad per hinge) of positions ``x`` (normalised) without a history: each on the branch
        (θ + 2πk) nearest its target at ``percent``.

        The measured angle wraps at ±180°; a crease folded past flat (a 180° target slightly overshot) would read as
        −179° and the solve would unfold it all the way round — for a bistable pattern into its other state. The
        branch nearest the target is the lowest-energy reading; from the flat sheet it is 0 for every |target| ≤ 180°.
        """
        raw = evaluate(self.model, x, None, 0.0, forces=False).theta
        target = self.model.targets(percent)
        return raw + 2.0 * np.pi * np.round((target - raw) / (2.0 * np.pi))

    def solve(
        self,
        percent: float = 1.0,
        *,
        start: np.ndarray | None = None,
        theta_prev: np.ndarray | None = None,
        velocities: np.ndarray | None = None,
        max_steps: int | None = None,
        stop_on_convergence: bool = True,
        continuation: bool | None = None,
    ) -> FoldResult:
        """Solve at fold percent ``percent`` (1.0 = 100 %) from ``start`` (mm, default flat).

        ``theta_prev`` (rad per hinge) carries the unwrapping history of a warm start; ``velocities`` (normalised
        units) carry the faithful integrator's state between animation frames. The fast methods fold from the flat
        sheet by continuation in the fold percent (:meth:`fold_steps`) unless ``continuation`` is False; given a
        ``start``, they solve once from it (``continuation=True`` is then refused).
        """
        if self.method != "faithful":
            return run_to_end(self.solve_steps(percent, start=start, theta_prev=theta_prev, continuation=continuation))
        s = self.settings
        model = self.model
        t0, c0 = time.perf_counter(), time.process_time()
        x0, theta_prev = self._start(start, theta_prev, percent)
        v0 = np.zeros_like(x0) if velocities is None else np.asarray(velocities, dtype=np.float64)
        x, v, theta, st = faithful_solve(
            model,
            x0,
            v0,
            theta_prev,
            percent,
            dt=self.dt,
            force_scale=self.force_scale,
            tolerance=s.tolerance,
            max_steps=s.max_steps if max_steps is None else max_steps,
            check_every=s.check_every,
            time_limit=s.time_limit,
            stop_on_convergence=stop_on_convergence,
        )
        energy = evaluate(model, x, theta, percent, forces=False).energy
        ms = (time.perf_counter() - t0) * 1000.0
        return FoldResult(
            positions=model.to_mm(x),
            fold_angles=self.edge_angles(theta),
            iterations=st.steps,
            force_evaluations=st.force_evaluations + 1,
            converged=st.converged,
            residual=st.residual,
            energy=energy,
            simulation_ms=ms,
            simulation_cpu_ms=(time.process_time() - c0) * 1000.0,
            message=st.message,
            method=self.method,
            theta=theta,
            velocities=v,
            dt=self.dt,
        )

    def _continues(self, start: np.ndarray | None, continuation: bool | None) -> bool:
        if continuation and start is not None:
            raise ValueError("a continuation starts from the flat sheet: give no start positions")
        return start is None if continuation is None else bool(continuation)

    def fold_steps(
        self, percent: float = 1.0, max_iterations: int | None = None
    ) -> Generator[SolveProgress, None, FoldResult]:
        """Fold from the flat sheet along the path paper takes: continuation in the fold percent, sliced.

        The natural path (:mod:`.path`): Newton solves at the fixed grid points ``±k · continuation_step`` up to the
        last one before ``percent``, then at ``percent``; each warm-started from the last state (extrapolated
        linearly in the percent from the last two, as the quasi-static animation does), the grid states to
        ``continuation_tolerance``, the last to ``tolerance``. Which of several equilibria a pattern reaches is then
        decided by the folding path, not by the first steps of one solve from the flat sheet: a static fold at P is
        the frame at P of any animation solved from the same path (:func:`.path.warm_startable`), deterministic
        (the solver's damping is restored from the path, tested bit-identical). The grid states are kept
        (:meth:`path_state`): a later fold or frame continues from them and reports the same counts as a fresh
        solve. At the end the exact Hessian's inertia is measured (``negative_pivots``: 0 for a stable minimum).
        Yields a :class:`SolveProgress` per Newton iteration. ``max_iterations`` (default the settings') caps the
        whole path; a grid state is kept only if it converged, so a capped fold never changes the path.

        Pins that only hold one triangle (:meth:`.Constraints.holds_pose_only`: a corner on the table) choose the
        pose, not the shape: the path is then folded free, each state shown posed on the pins, and the last one is
        posed and solved once more with the pins fixed. Held by them all along, Newton had to swing the whole sheet
        about the small anchor at every step (46 iterations against 14 free on examples/single_curve.svg).

        The result and every position shown are placed with the sheet's centre face on the table (:meth:`_placed`).
        """
        return (yield from self._placed_steps(self._path_steps(percent, max_iterations)))

    def _path_steps(
        self, percent: float = 1.0, max_iterations: int | None = None
    ) -> Generator[SolveProgress, None, FoldResult]:
        """The continuation of :meth:`fold_steps`, its result where the damped steps left it."""
        s = self.settings
        model = self.model
        t0, c0 = time.perf_counter(), time.process_time()
        percent = float(percent)
        n = path.steps_to(percent, s.continuation_step)
        anchor = self.constraints is not None and self.constraints.holds_pose_only(self.mesh)
        first = percent if n == 1 else path.grid_point(1, percent, s.continuation_step)
        flat = path.PathState(0.0, *self._start(None, None, first), 1e-3, {})  # pins placed, if any
        states = [flat]  # the path's states at grid points 0 … k
        totals = dict(iterations=0, evaluations=0, assemblies=0, solves=0, exact=0, saddles=0)
        reused = 0

        def stage(
            x0: np.ndarray, t_start: np.ndarray, p: float, tolerance: float, pinned: bool, tail: float | None = None
        ):
            """One Newton solve of the path, its iterations numbered on from the last and its counts added up
            (``tail``: the residual below which it tries the exact Hessian, default :data:`.newton.TAIL_RESIDUAL`)."""
            cap = s.max_iterations if max_iterations is None else max_iterations
            budget = max(cap - totals["iterations"], 0)  # max_iterations caps the whole path
            steps = self._fast_steps(
                x0,
                t_start,
                p,
                t0,
                tolerance=tolerance,
                max_iterations=budget,
                check_minimum=True,
                pinned=pinned,
                tail_residual=tail,
            )
            while True:
                try:
                    progress = next(steps)
                except StopIteration as done:
                    r = done.value
                    break
                shown = progress.positions if pinned else self._posed(progress.positions)
                yield SolveProgress(totals["iterations"] + progress.iteration, progress.residual, shown)
            totals["iterations"] += r.iterations
            totals["evaluations"] += r.force_evaluations
            totals["assemblies"] += r.hessian_assemblies
            totals["solves"] += r.linear_solves
            totals["exact"] += r.exact_iterations
            totals["saddles"] += r.saddle_escapes
            return r

        def predicted(p: float) -> tuple[np.ndarray, np.ndarray]:
            """The start of the solve at ``p``: the last state, extrapolated from the last two (a predictor)."""
            last, before = states[-1], (states[-2] if len(states) > 1 else None)
            return path.extrapolate(
                p, (last.percent, last.x, last.theta), before and (before.percent, before.x, before.theta)
            )

        halved: list[float] = []
        retried: list[float] = []

        def stalled(r: FoldResult) -> bool:
            return not r.converged and r.message.startswith("stalled")

        def reach(p: float, tolerance: float, halvings: int = 0):
            """Solve at ``p`` from the last state, appending it to ``states``. A stage that stalls ("no descent
            step") is solved again with the exact Hessian from its first iteration (:data:`path.EXACT_RETRY`) and, if
            that stalls too, taken again in two halves, up to :data:`path.MAX_HALVINGS` times."""
            x0, t_start = predicted(p)
            self.lm_lambda = states[-1].lm_lambda
            r = yield from stage(x0, t_start, p, tolerance, pinned=not anchor)
            if path.EXACT_RETRY and stalled(r):
                retried.append(p)  # the stage again, exact Newton from its first iteration
                self.lm_lambda = states[-1].lm_lambda
                r = yield from stage(x0, t_start, p, tolerance, pinned=not anchor, tail=math.inf)
            if stalled(r) and halvings < path.MAX_HALVINGS:
                halved.append(p)
                mid = states[-1].percent + 0.5 * (p - states[-1].percent)
                half = yield from reach(mid, max(s.tolerance, s.continuation_tolerance), halvings + 1)
                if half.converged:
                    return (yield from reach(p, tolerance, halvings + 1))
                states.pop()  # the half did not help: report the stage as it stalled
            saddles = states[-1].saddle_percents + ([p] if r.saddle_escapes else [])
            states.append(path.PathState(p, model.from_mm(r.positions), r.theta, self.lm_lambda, dict(totals), saddles))
            return r

        for k in range(1, n + 1):
            p = percent if k == n else path.grid_point(k, percent, s.continuation_step)
            kept = self._path.get(p) if k < n else None
            if kept is not None:
                states.append(kept)
                totals = dict(kept.totals)
                reused = kept.totals["iterations"]
                continue
            tolerance = s.tolerance if k == n else max(s.tolerance, s.continuation_tolerance)
            r = yield from reach(p, tolerance)
            if k < n and r.converged and s.time_limit is None:  # a state cut short by the clock is not the path
                self._path[p] = states[-1]
        x, theta = states[-1].x, states[-1].theta
        if anchor:  # the free fold posed on the pins, then held by them
            posed = self.constraints.pose(r.positions, self.mesh.vertices_3d, exact=True)
            r = yield from stage(model.from_mm(posed), theta, percent, s.tolerance, pinned=True)
            x, theta = model.from_mm(r.positions), r.theta
        with single_threaded_blas():
            negative = self.negative_pivots(x, theta, percent)
        last_step, r.iterations = r.iterations, totals["iterations"]
        if last_step != r.iterations:  # the stage's message counted its own: say the whole path's, as the report does
            r.message = r.message.replace(
                f"after {last_step} iterations", f"after {r.iterations} iterations ({last_step} in the last step)", 1
            )
        r.force_evaluations = totals["evaluations"]
        r.hessian_assemblies = totals["assemblies"] + 1
        r.linear_solves = totals["solves"]
        r.exact_iterations = totals["exact"]
        r.saddle_escapes = totals["saddles"]
        r.saddle_percents = states[-1].saddle_percents
        r.continuation_steps = n
        r.reused_iterations = reused
        r.negative_pivots = negative
        r.simulation_ms = (time.perf_counter() - t0) * 1000.0
        r.simulation_cpu_ms = (time.process_time() - c0) * 1000.0
        stalls = f", {len(retried)} retried with exact Newton" if retried else ""
        stalls += f", {len(halved)} halved" if halved else ""
        stalls += " after a stall" if stalls else ""
        r.message = f"{r.message} (continuation from the flat sheet in {n} fold-percent steps{stalls})"
        return r

    @property
    def _path(self) -> dict[float, path.PathState]:
        """The natural path's states at grid points (see :meth:`fold_steps`), for the current settings and pins."""
        key = (repr(self.settings), id(self.constraints))
        if self._path_key != key:
            self._path_key, self._path_states = key, {}
        return self._path_states

    def path_state(self, percent: float) -> tuple[float, np.ndarray, np.ndarray] | None:
        """``(grid point, positions mm, θ)`` of the natural path's state at the last grid point before ``percent``
        (the flat sheet within the first step), if it has been computed: the predictor's second point for a frame
        solved from the path, placed as the frames are (:meth:`_placed`)."""
        g = path.grid_below(percent, self.settings.continuation_step)
        if g == 0.0:
            x, theta = self._start(None, None, percent)
            return 0.0, self._placed(self.model.to_mm(x)), theta
        kept = self._path.get(g)
        return None if kept is None else (g, self._placed(self.model.to_mm(kept.x)), kept.theta)

    def _posed(self, positions: np.ndarray) -> np.ndarray:
        """Free-fold ``positions`` (mm) posed on the pins (:meth:`.Constraints.pose`, from the flat sheet)."""
        return self.constraints.pose(positions, self.mesh.vertices_3d)

    def negative_pivots(self, x: np.ndarray, theta: np.ndarray, percent: float) -> int | None:
        """Number of negative eigenvalues of the exact Hessian at ``x`` (normalised): 0 at a stable minimum.

        Counted from the pivots of its block factorisation, shifted by ``newton.inertia_shift`` (1e-7 of the force
        scale, which lifts the translations, and the rotations' curvature) as ``newton_steps`` measures a converged
        state; ``None`` if the matrix cannot be factored."""
        ev = evaluate(self.model, x, theta, percent, jacobians=True)
        H = self.assembler.assemble_exact(x, ev)
        # pinned degrees of freedom are decoupled; without pins the rigid rotations' curvature (∝ the residual
        # force, not a buckling mode) is lifted
        pins = None if self.constraints is None else self.constraints.fixed_mask(self.model.n_nodes)
        fx = Fixed.of(pins, self.force_scale)
        shift = fx.shift(inertia_shift(x, ev.forces, self.force_scale, fx))
        try:
            return self.assembler.matrix.factor(H, shift, inertia=True).negative_pivots
        except np.linalg.LinAlgError:
            return None

    def solve_steps(
        self,
        percent: float = 1.0,
        *,
        start: np.ndarray | None = None,
        theta_prev: np.ndarray | None = None,
        continuation: bool | None = None,
        max_iterations: int | None = None,
    ) -> Generator[SolveProgress, None, FoldResult]:
        """The fast solve of :meth:`solve`, one Newton iteration per ``next``: yields a :class:`SolveProgress`
        (iteration, residual, positions in mm) after each, returns the :class:`FoldResult` (``StopIteration.value``).

        For callers that work in slices and may stop between any two iterations (Blender's modal jobs); the result
        equals :meth:`solve`'s. Only the fast methods step this way (the faithful one is sliced by ``max_steps``).
        ``max_iterations`` caps this solve (default: the settings'), e.g. a timeline frame."""
        if self.method == "faithful":
            raise ValueError("solve_steps steps the fast solver; slice the faithful one with solve(max_steps=...)")
        if self._continues(start, continuation):
            return (yield from self.fold_steps(percent, max_iterations))
        t0 = time.perf_counter()
        x0, theta_prev = self._start(start, theta_prev, percent)
        return (
            yield from self._placed_steps(
                self._fast_steps(
                    x0, theta_prev, percent, t0, max_iterations=max_iterations, check_minimum=start is None
                )
            )
        )

    def frame_steps(
        self,
        percent: float,
        start: np.ndarray | None,
        theta_prev: np.ndarray | None,
        warm_iterations: int,
        path_iterations: int | None = None,
        fall_back: bool = True,
    ) -> Generator[SolveProgress, None, FoldResult]:
        """One frame of a quasi-static animation, sliced like :meth:`solve_steps`: warm from ``start`` (mm, the
        solved frame before, extrapolated) in at most ``warm_iterations``; from the natural path in at most
        ``path_iterations`` (default the settings') when ``start`` is ``None`` — and, with ``fall_back``, when the
        warm solve did not converge in its cap (:data:`.path.WARM_MAX_ITERATIONS`: it lost the branch it followed).
        A frame from the path is the static fold at ``percent`` (``continuation_steps`` > 0); its ``iterations``
        count the warm ones too. :class:`.animation.FoldAnimation` and the timeline's frames both solve through
        here; playback, capped and synchronous, does not fall back."""
        if start is not None:
            warm = yield from self.solve_steps(
                percent, start=start, theta_prev=theta_prev, max_iterations=warm_iterations
            )
            if warm.converged or not fall_back:
                return warm
        r = yield from self.solve_steps(percent, max_iterations=path_iterations)
        if start is not None:
            r.iterations += warm.iterations
        return r

    def _start(self, start: np.ndarray | None, theta_prev: np.ndarray | None, percent: float):
        model = self.model
        x0 = model.rest.copy() if start is None else model.from_mm(start)
        if x0.shape != model.rest.shape or not np.all(np.isfinite(x0)):
            raise SolverError(f"start positions must be a finite ({model.n_nodes}, 3) array, got shape {x0.shape}")
        if self.constraints is not None:
            x0 = model.from_mm(self.constraints.place_pins(model.to_mm(x0)))
        if theta_prev is None:
            theta_prev = self.start_angles(x0, percent)
        return x0, theta_prev

    def _fast_steps(
        self,
        x0: np.ndarray,
        theta_prev: np.ndarray,
        percent: float,
        t0: float,
        tolerance: float | None = None,
        max_iterations: int | None = None,
        check_minimum: bool = False,
        pinned: bool = True,
        tail_residual: float | None = None,
    ) -> Generator[SolveProgress, None, FoldResult]:
        """One Newton solve. From the flat sheet (continuation stages, ``check_minimum``) the exact tail starts at
        residual ``TAIL_RESIDUAL`` and a converged state must be a minimum; a warm start from an earlier equilibrium
        (animation frames, live re-folds) is a small correction that one Gauss–Newton step usually makes, so there the
        exact Hessian is used only when Gauss–Newton is slow. ``tail_residual`` overrides where the exact tail starts
        (a stalled path stage is retried with ``math.inf``: exact from the first iteration). ``pinned`` false:
        without the pins' fixed degrees of freedom (the free fold of pins that hold only the pose,
        :meth:`fold_steps`)."""
        c0 = time.process_time()
        model = self.model
        steps = self._newton(x0, theta_prev, percent, tolerance, max_iterations, check_minimum, pinned, tail_residual)
        while True:
            with single_threaded_blas():  # per step: never left on while the caller holds the generator
                try:
                    progress = next(steps)
                except StopIteration as done:
                    x, theta, ev, st, lam = done.value
                    break
            yield SolveProgress(progress.iteration, progress.residual, model.to_mm(progress.x))
        self.lm_lambda = min(max(lam, 1e-6), 1e-2)
        if not np.all(np.isfinite(x)):
            raise SolverError(f"fast solver produced non-finite positions ({st.message})")
        ms = (time.perf_counter() - t0) * 1000.0
        return FoldResult(
            simulation_cpu_ms=(time.process_time() - c0) * 1000.0,
            positions=model.to_mm(x),
            fold_angles=self.edge_angles(theta),
            iterations=st.iterations,
            force_evaluations=st.force_evaluations + st.energy_evaluations,
            converged=st.converged,
            residual=st.residual,
            energy=ev.energy,
            simulation_ms=ms,
            message=st.message,
            method=self.method,
            hessian_assemblies=st.hessian_assemblies,
            linear_solves=st.linear_solves,
            theta=theta,
            exact_iterations=st.exact_iterations,
            saddle_escapes=st.saddle_escapes,
            negative_pivots=st.negative_pivots if st.exact_iterations or st.saddle_escapes else None,
        )

    def _newton(
        self,
        x0: np.ndarray,
        theta_prev: np.ndarray,
        percent: float,
        tolerance: float | None = None,
        max_iterations: int | None = None,
        check_minimum: bool = False,
        pinned: bool = True,
        tail_residual: float | None = None,
    ):
        s = self.settings
        model = self.model
        return newton_steps(
            model,
            x0,
            theta_prev,
            percent,
            force_scale=self.force_scale,
            tolerance=s.tolerance if tolerance is None else tolerance,
            max_iterations=s.max_iterations if max_iterations is None else max_iterations,
            assembler=self.assembler,
            time_limit=s.time_limit,
            lm_lambda=self.lm_lambda,
            fixed=None if self.constraints is None or not pinned else self.constraints.fixed_mask(model.n_nodes),
            exact_tail=s.exact_tail,
            check_minimum=check_minimum,
            tail_residual=(TAIL_RESIDUAL if check_minimum else 0.0) if tail_residual is None else tail_residual,
        )


def solve(
    mesh: FoldMesh,
    percent: float = 1.0,
    method: str = "fast",
    settings: SolverSettings | None = None,
    start: np.ndarray | None = None,
) -> FoldResult:
    """Fold ``mesh`` to equilibrium at ``percent`` (1.0 = 100 %) with ``method`` (see module docstring).

    ``start`` (``(n, 3)`` mm) warm-starts the solve; default is the flat sheet. Raises :class:`SolverError` on
    divergence; a run that hits its iteration/step/time cap returns with ``converged=False`` and the residual reached.
    """
    return Solver(mesh, settings, method).solve(percent, start=start)


def rigid_rms(a: np.ndarray, b: np.ndarray) -> float:
    """RMS distance between point sets ``a`` and ``b`` (``(n, 3)``) after the best rigid (Kabsch) alignment of ``a``
    onto ``b`` (rotation without reflection)."""
    a = np.asarray(a, dtype=np.float64)
    b = np.asarray(b, dtype=np.float64)
    rot, shift = rigid_fit(a, b)
    return float(np.sqrt(np.mean(np.sum((a @ rot + shift - b) ** 2, axis=1))))
