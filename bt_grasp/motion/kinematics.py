"""Forward and inverse kinematics of the UR5 + gripper in the robot base frame (pinocchio).

The merged URDF has eight joints: six arm joints and two finger joints (one mimics the other). The
arm model here is pinocchio's *reduced* model with both finger joints locked at a given opening, so it
has exactly 6 DoF in ``ARM_JOINTS`` order and its finger frames sit where the fingers are at that
opening. Every pose is ``T_base_<frame>`` with ``base`` = ``base_link`` (the URDF root); the world to
base transform is ``Scene.T_world_base()``.

IK is damped least squares on the SE(3) log error of the tcp (the classic CLIK iteration), projected
on the joint limits, from several seeds: ``q_current`` first, then random seeds from a caller-given
generator. An unreachable pose is a result value, never an exception. For a UR-shaped arm (this one),
``closed_form_ik`` gives *every* solution of a pose (``analytic_ik.py``); the planner's goal sets use it.
"""

from __future__ import annotations

import enum
import logging
from collections.abc import Iterator
from dataclasses import dataclass
from functools import cache, cached_property
from pathlib import Path
from typing import Protocol

import numpy as np
import pinocchio as pin
from numpy.typing import NDArray

from bt_grasp.geometry import Mat4
from bt_grasp.motion.analytic_ik import SOLUTION_TOL, URAnalyticIK, ur_analytic_ik
from bt_grasp.robot_description import (
    ARM_JOINTS,
    FINGER_JOINT,
    MAX_OPENING_M,
    MIMIC_FINGER_JOINT,
    TCP_LINK,
    robot_urdf_path,
)

log = logging.getLogger(__name__)

Vec = NDArray[np.float64]

#: IK convergence tolerances
IK_POSITION_TOL_M = 1e-5
IK_ROTATION_TOL_RAD = 1e-4


class IKStatus(enum.Enum):
    OK = "ok"
    UNREACHABLE = "unreachable"  # no seed converged within the tolerances and the joint limits
    INVALID_INPUT = "invalid_input"  # not a finite rigid transform, or a bad q_current


@dataclass(frozen=True)
class IKResult:
    """Outcome of an IK query. ``q`` is the best configuration found (the seed's end point when not OK)."""

    status: IKStatus
    q: Vec
    position_error_m: float
    rotation_error_rad: float
    iterations: int  # total DLS iterations over all seeds tried

    @property
    def ok(self) -> bool:
        return self.status is IKStatus.OK


@dataclass(frozen=True)
class IKOptions:
    """Tuning of the damped-least-squares iteration."""

    max_iterations: int = 60  # per seed (a converging seed needs ~10-30; about half of random seeds converge)
    damping: float = 1e-6  # Levenberg damping added to J J^T
    max_step_rad: float = 1.0  # largest joint change per iteration (max norm)
    position_tol_m: float = IK_POSITION_TOL_M
    rotation_tol_rad: float = IK_ROTATION_TOL_RAD
    distinct_tol_rad: float = 1e-3  # two solutions closer than this (max norm) are the same


def is_rigid_transform(T: NDArray[np.float64], tol: float = 1e-6) -> bool:
    """A finite 4x4 homogeneous transform with an orthonormal, right-handed rotation."""
    T = np.asarray(T, dtype=float)
    if T.shape != (4, 4) or not np.all(np.isfinite(T)):
        return False
    R = T[:3, :3]
    return bool(
        np.allclose(R.T @ R, np.eye(3), atol=tol * 100)
        and abs(np.linalg.det(R) - 1.0) < tol * 100
        and np.allclose(T[3], [0, 0, 0, 1], atol=tol)
    )


class ArmKinematics:
    """The 6-DoF arm model (fingers locked at ``opening_m``) with FK and multi-seed DLS IK."""

    def __init__(self, opening_m: float = MAX_OPENING_M, urdf_path: Path | None = None) -> None:
        if not 0.0 <= opening_m <= MAX_OPENING_M:
            raise ValueError(f"gripper opening must be within [0, {MAX_OPENING_M}] m, got {opening_m}")
        self.opening_m = float(opening_m)
        self.urdf_path = Path(urdf_path) if urdf_path is not None else robot_urdf_path()
        full = pin.buildModelFromUrdf(str(self.urdf_path))
        self.full_model = full
        q_ref = pin.neutral(full)
        lock = []
        for name in (FINGER_JOINT, MIMIC_FINGER_JOINT):
            jid = full.getJointId(name)
            q_ref[full.joints[jid].idx_q] = self.opening_m / 2
            lock.append(jid)
        self.q_reference_full = q_ref
        self.locked_joint_ids = tuple(lock)
        self.model: pin.Model = pin.buildReducedModel(full, lock, q_ref)
        names = tuple(self.model.names[1:])
        if names != ARM_JOINTS:
            raise RuntimeError(f"reduced model joints {names} are not the arm joints {ARM_JOINTS}")
        self.data = self.model.createData()
        self.lower_rad: Vec = np.array(self.model.lowerPositionLimit, dtype=float)
        self.upper_rad: Vec = np.array(self.model.upperPositionLimit, dtype=float)
        self._tcp_id = self.model.getFrameId(TCP_LINK)
        self.link_names: tuple[str, ...] = tuple(
            f.name for f in self.model.frames if f.type == pin.FrameType.BODY
        )
        # an upper bound of the tcp's distance from the first joint's origin (fixed in the base frame)
        self._shoulder_xyz_m: Vec = np.array(self.model.jointPlacements[1].translation)
        chain = sum(float(np.linalg.norm(self.model.jointPlacements[j].translation)) for j in range(2, 7))
        tcp_offset = float(np.linalg.norm(self.model.frames[self._tcp_id].placement.translation))
        self.reach_bound_m = chain + tcp_offset

    # --- forward kinematics -------------------------------------------------------------------------
    def _check_q(self, q: NDArray[np.float64]) -> Vec:
        q = np.asarray(q, dtype=float).reshape(-1)
        if q.shape != (6,) or not np.all(np.isfinite(q)):
            raise ValueError(f"a configuration is 6 finite joint angles, got {q!r}")
        return q

    def frame_id(self, link: str) -> int:
        if not self.model.existFrame(link):
            raise KeyError(f"no link '{link}' in the robot model; links: {', '.join(self.link_names)}")
        return int(self.model.getFrameId(link))

    def fk(self, q: NDArray[np.float64]) -> Mat4:
        """``T_base_tcp`` for the arm configuration ``q`` (rad, ``ARM_JOINTS`` order)."""
        return self.fk_link(q, TCP_LINK)

    def fk_link(self, q: NDArray[np.float64], link: str) -> Mat4:
        """``T_base_<link>`` for any link (or frame) of the model."""
        fid = self.frame_id(link)
        q = self._check_q(q)
        pin.framesForwardKinematics(self.model, self.data, q)
        return np.array(self.data.oMf[fid].homogeneous)

    def fk_all(self, q: NDArray[np.float64]) -> dict[str, Mat4]:
        """``T_base_<link>`` of every link, from one FK pass."""
        q = self._check_q(q)
        pin.framesForwardKinematics(self.model, self.data, q)
        return {n: np.array(self.data.oMf[self.model.getFrameId(n)].homogeneous) for n in self.link_names}

    def within_limits(self, q: NDArray[np.float64]) -> bool:
        q = np.asarray(q, dtype=float)
        return bool(np.all(q >= self.lower_rad - 1e-9) and np.all(q <= self.upper_rad + 1e-9))

    # --- inverse kinematics -------------------------------------------------------------------------
    def _solve_from(self, oMdes: pin.SE3, q0: Vec, opts: IKOptions) -> tuple[Vec, float, float, int, bool]:
        model, data, fid = self.model, self.data, self._tcp_id
        q = np.clip(q0, self.lower_rad, self.upper_rad)
        pos_err = rot_err = float("inf")
        damping = opts.damping * np.eye(6)
        target = oMdes.translation
        for it in range(1, opts.max_iterations + 1):
            pin.computeJointJacobians(model, data, q)  # forward kinematics + joint Jacobians, one pass
            oMf = pin.updateFramePlacement(model, data, fid)
            fMdes = oMf.actInv(oMdes)
            err = pin.log6(fMdes).vector  # error twist in the tcp frame
            pos_err = float(np.linalg.norm(target - oMf.translation))
            rot_err = float(np.linalg.norm(err[3:]))
            if pos_err < opts.position_tol_m and rot_err < opts.rotation_tol_rad:
                return q, pos_err, rot_err, it - 1, True
            J = pin.Jlog6(fMdes) @ pin.getFrameJacobian(model, data, fid, pin.ReferenceFrame.LOCAL)
            dq = J.T @ np.linalg.solve(J @ J.T + damping, err)
            step = float(np.max(np.abs(dq)))
            if step > opts.max_step_rad:
                dq *= opts.max_step_rad / step
            q = np.clip(q + dq, self.lower_rad, self.upper_rad)
        return q, pos_err, rot_err, opts.max_iterations, False

    def _unwrap_towards(self, q: Vec, q_ref: Vec) -> Vec:
        """Shift each joint by whole turns towards ``q_ref`` while staying within the limits."""
        q = q.copy()
        for j in range(6):
            turns = np.round((q_ref[j] - q[j]) / (2 * np.pi))
            if turns:
                candidate = q[j] + turns * 2 * np.pi
                if self.lower_rad[j] <= candidate <= self.upper_rad[j]:
                    q[j] = candidate
        return q

    def iter_ik_solutions(
        self,
        T_base_tcp_goal: Mat4,
        q_current: NDArray[np.float64],
        *,
        seeds: int,
        rng: np.random.Generator,
        options: IKOptions | None = None,
        tried: list[IKResult] | None = None,
    ) -> Iterator[Vec]:
        """Distinct solutions in the order the seeds find them (``q_current`` first, then ``rng``'s draws).

        A fixed amount of work per seed (``options.max_iterations``), ``seeds`` seeds at most: the caller
        stops whenever it has enough. The input must be valid (see :meth:`ik_solutions`). ``tried``, when
        given, receives one :class:`IKResult` per seed (for the best-error report of a failure).
        """
        opts = options or IKOptions()
        q_cur = np.asarray(q_current, dtype=float).reshape(-1)
        oMdes = pin.SE3(np.asarray(T_base_tcp_goal, dtype=float))
        found: list[Vec] = []
        for k in range(seeds):
            q0 = q_cur if k == 0 else rng.uniform(self.lower_rad, self.upper_rad)
            q, pe, re, iters, ok = self._solve_from(oMdes, q0, opts)
            if tried is not None:
                tried.append(IKResult(IKStatus.OK if ok else IKStatus.UNREACHABLE, q, pe, re, iters))
            if not ok:
                continue
            q = self._unwrap_towards(q, q_cur)
            if all(np.max(np.abs(q - s)) > opts.distinct_tol_rad for s in found):
                found.append(q)
                yield q

    @cached_property
    def _closed_form(self) -> URAnalyticIK | None:
        placements = [np.array(self.model.jointPlacements[j].translation) for j in range(1, 7)]
        return ur_analytic_ik(self.fk, placements, np.array(self.model.frames[self._tcp_id].placement.translation))

    @property
    def has_closed_form_ik(self) -> bool:
        return self._closed_form is not None

    def closed_form_ik(self, T_base_tcp_goal: Mat4, q_ref: NDArray[np.float64]) -> list[Vec] | None:
        """Every IK solution of the pose within the joint limits, closest to ``q_ref`` first; None if no closed form.

        Each solution takes, per joint, the whole turn nearest ``q_ref`` (joints of +-2 pi have two; the
        geometry, hence collision, is the same). At the wrist singularity the last joint keeps ``q_ref``'s
        angle. The pose's rotation is first projected onto the nearest rotation (a pose built from a measured,
        slightly tilted frame passes ``is_rigid_transform`` at 1e-4 but is not exactly orthonormal), and every
        solution is checked through :meth:`fk` (1e-7) before it is returned.
        """
        solver = self._closed_form
        if solver is None:
            return None
        q_ref = self._check_q(q_ref)
        T = np.array(T_base_tcp_goal, dtype=float)
        U, _, Vt = np.linalg.svd(T[:3, :3])
        T[:3, :3] = U @ Vt
        out: list[Vec] = []
        for q in solver.raw_solutions(T, float(q_ref[5])):
            q = self._unwrap_towards(np.mod(q + np.pi, 2 * np.pi) - np.pi, q_ref)
            if not self.within_limits(q) or not np.allclose(self.fk(q), T, atol=SOLUTION_TOL):
                continue
            if all(np.max(np.abs(q - s)) > 1e-6 for s in out):
                out.append(q)
        out.sort(key=lambda s: float(np.linalg.norm(s - q_ref)))
        return out

    def beyond_reach_m(self, T_base_tcp_goal: Mat4) -> float:
        """How far the tcp position lies beyond a proven reach bound (<= 0: maybe reachable)."""
        reach = float(np.linalg.norm(np.asarray(T_base_tcp_goal)[:3, 3] - self._shoulder_xyz_m))
        return reach - self.reach_bound_m

    def ik_solutions(
        self,
        T_base_tcp_goal: Mat4,
        q_current: NDArray[np.float64],
        *,
        seeds: int = 8,
        rng: np.random.Generator | None = None,
        options: IKOptions | None = None,
        max_solutions: int | None = None,
        stop_if_current_converges: bool = False,
    ) -> tuple[list[Vec], IKResult]:
        """All distinct solutions found from ``seeds`` starts, closest to ``q_current`` first.

        Returns (solutions, best) where ``best`` is the :class:`IKResult` of the closest solution (or the
        best failed attempt). ``rng`` draws the random seeds; None uses a generator seeded with 0 so that a
        call is always reproducible. ``max_solutions`` stops early once that many distinct solutions exist;
        ``stop_if_current_converges`` stops when the first seed (``q_current``) converges: that solution is
        reached continuously from ``q_current`` and is, in practice, the closest one.
        """
        q_cur = np.asarray(q_current, dtype=float).reshape(-1)
        if q_cur.shape != (6,) or not np.all(np.isfinite(q_cur)) or not is_rigid_transform(T_base_tcp_goal):
            bad = IKResult(IKStatus.INVALID_INPUT, np.full(6, np.nan), float("inf"), float("inf"), 0)
            return [], bad
        if seeds < 1:
            raise ValueError("ik needs at least one seed")
        rng = rng if rng is not None else np.random.default_rng(0)
        beyond_m = self.beyond_reach_m(T_base_tcp_goal)
        if beyond_m > 0:
            return [], IKResult(IKStatus.UNREACHABLE, q_cur.copy(), beyond_m, float("inf"), 0)
        tried: list[IKResult] = []
        solutions: list[Vec] = []
        for q in self.iter_ik_solutions(T_base_tcp_goal, q_cur, seeds=seeds, rng=rng, options=options,
                                        tried=tried):
            solutions.append(q)
            if max_solutions is not None and len(solutions) >= max_solutions:
                break
            if len(tried) == 1 and stop_if_current_converges:
                break
        total_iters = sum(t.iterations for t in tried)
        if not solutions:
            worst = min(tried, key=lambda t: t.position_error_m + t.rotation_error_rad)
            return [], IKResult(IKStatus.UNREACHABLE, worst.q, worst.position_error_m, worst.rotation_error_rad,
                                total_iters)
        solutions.sort(key=lambda s: float(np.linalg.norm(s - q_cur)))
        closest = solutions[0]
        match = min((t for t in tried if t.ok), key=lambda t: float(np.max(np.abs(
            self._unwrap_towards(t.q, q_cur) - closest))))
        return solutions, IKResult(IKStatus.OK, closest, match.position_error_m, match.rotation_error_rad,
                                   total_iters)

    def ik(
        self,
        T_base_tcp_goal: Mat4,
        q_current: NDArray[np.float64],
        *,
        seeds: int = 8,
        rng: np.random.Generator | None = None,
        options: IKOptions | None = None,
    ) -> IKResult:
        """The IK solution closest to ``q_current`` (joint-space Euclidean distance).

        The first seed is ``q_current``; when it converges its solution is returned at once. Otherwise
        up to ``seeds - 1`` random seeds from ``rng`` run and the closest of their solutions wins.
        """
        _, best = self.ik_solutions(
            T_base_tcp_goal, q_current, seeds=seeds, rng=rng, options=options, stop_if_current_converges=True
        )
        return best


def other_robot(urdf_path: Path | None) -> Path | None:
    """``urdf_path`` unless it is bt_grasp's own robot description (then None): the one key of the shared models."""
    if urdf_path is None or Path(urdf_path) == robot_urdf_path():
        return None
    return Path(urdf_path)


def default_kinematics(opening_m: float = MAX_OPENING_M, urdf_path: Path | None = None) -> ArmKinematics:
    """A shared model per gripper opening and robot description (building one parses the URDF: ~10 ms);
    ``urdf_path``: the robot with another gripper (``bt_grasp.cell.grippers``), None: bt_grasp's own."""
    return _shared_kinematics(opening_m, other_robot(urdf_path))


@cache
def _shared_kinematics(opening_m: float, urdf_path: Path | None) -> ArmKinematics:
    return ArmKinematics(opening_m, urdf_path)


class KinematicModel(Protocol):
    """What callers need of the arm's kinematics: :class:`ArmKinematics`, or a wrapper of it (a fault's)."""

    @property
    def opening_m(self) -> float: ...

    @property
    def urdf_path(self) -> Path:
        """The robot description the model was built from (its gripper's geometry and TCP)."""
        ...

    def fk(self, q: NDArray[np.float64]) -> Mat4: ...

    def fk_link(self, q: NDArray[np.float64], link: str) -> Mat4: ...

    def ik(
        self,
        T_base_tcp_goal: Mat4,
        q_current: NDArray[np.float64],
        *,
        seeds: int = 8,
        rng: np.random.Generator | None = None,
        options: IKOptions | None = None,
    ) -> IKResult: ...

    def ik_solutions(
        self,
        T_base_tcp_goal: Mat4,
        q_current: NDArray[np.float64],
        *,
        seeds: int = 8,
        rng: np.random.Generator | None = None,
        options: IKOptions | None = None,
        max_solutions: int | None = None,
        stop_if_current_converges: bool = False,
    ) -> tuple[list[Vec], IKResult]: ...


class SeededKinematics:
    """A :class:`KinematicModel` whose IK restarts draw from a run's stream (``bt_grasp.seeds.Stream.IK``) when a
    caller gives no generator: each call a fresh generator on the same seed, as the model's own default (seed 0)
    does, but the run's. Everything else is the wrapped model's."""

    def __init__(self, inner: KinematicModel, seed: int) -> None:
        self.inner = inner
        self.seed = int(seed)

    @property
    def opening_m(self) -> float:
        return self.inner.opening_m

    @property
    def urdf_path(self) -> Path:
        return self.inner.urdf_path

    def fk(self, q: NDArray[np.float64]) -> Mat4:
        return self.inner.fk(q)

    def fk_link(self, q: NDArray[np.float64], link: str) -> Mat4:
        return self.inner.fk_link(q, link)

    def _rng(self, rng: np.random.Generator | None) -> np.random.Generator:
        return rng if rng is not None else np.random.default_rng(self.seed)

    def ik(self, T_base_tcp_goal: Mat4, q_current: NDArray[np.float64], *, seeds: int = 8,
           rng: np.random.Generator | None = None, options: IKOptions | None = None) -> IKResult:
        return self.inner.ik(T_base_tcp_goal, q_current, seeds=seeds, rng=self._rng(rng), options=options)

    def ik_solutions(
        self, T_base_tcp_goal: Mat4, q_current: NDArray[np.float64], *, seeds: int = 8,
        rng: np.random.Generator | None = None, options: IKOptions | None = None, max_solutions: int | None = None,
        stop_if_current_converges: bool = False,
    ) -> tuple[list[NDArray[np.float64]], IKResult]:
        return self.inner.ik_solutions(T_base_tcp_goal, q_current, seeds=seeds, rng=self._rng(rng),
                                       options=options, max_solutions=max_solutions,
                                       stop_if_current_converges=stop_if_current_converges)
