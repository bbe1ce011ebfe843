"""A motion model of an object riding a conveyor belt: where it will be at a given time, and how sure that is.

An object on a running belt moves with the belt: along the belt's axis at the belt's speed, never across it, never
turning (until something takes it off). So the tracker estimates one coordinate, ``s`` (metres along the belt
from its upstream end, base frame), with a constant-velocity model; where the object lies across the belt, its
height, yaw and size are constant and averaged over the detections.

* **Vision only** (no encoder): a Kalman filter on ``[s, v]``. The first detection starts it with the belt's
  nominal speed (installation data) as a wide prior on ``v`` (:data:`SPEED_PRIOR_SHARE` of it, plus
  :data:`SPEED_PRIOR_FLOOR_M_S`); each detection (a position along the belt, stamped with its frame's time) is
  one update; white acceleration noise (:data:`ACCEL_NOISE_M_S2`) lets the speed drift as a real belt's does.
* **With the belt's encoder**: the belt's travel ``E(t)`` is measured (``bt_grasp.interfaces.Encoder``), so the
  object's position is ``s(t) = s0 + E(t)`` and only ``s0`` is unknown: each detection gives
  ``z - E(t_frame)``, averaged with the variance of the detections; the encoder's speed, from its last
  :data:`ENCODER_WINDOW_S` of readings, carries ``E`` past its last reading.

Detections arrive late (the cell's perception latency) but stamped with their frames' times, so they are applied
at those times; ``predict(t)`` answers for any later time. Its ``sigma_m`` is the one-sigma error of the position
along the belt (the model's covariance: position, speed, and the time carried forward).

Everything here is arithmetic on detections and encoder readings; no simulator truth.
"""

from __future__ import annotations

from collections import deque
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray

from bt_grasp.perception.results import Detection

Vec3 = NDArray[np.float64]

#: one detection's error along the belt, 1 sigma, m (the pipeline measured 0.3 mm of noise and up to 0.8 mm of
#: bias on the belt at 1 m from the fixed camera: docs/following.md; a wrist camera's is smaller)
MEASUREMENT_SIGMA_M = 0.001
#: the belt's speed drifts as white acceleration noise of this density, m/s^2 (a real belt under load)
ACCEL_NOISE_M_S2 = 0.02
#: the prior on the speed before the second detection: this share of the belt's nominal speed ...
SPEED_PRIOR_SHARE = 0.25
#: ... plus this, m/s
SPEED_PRIOR_FLOOR_M_S = 0.02
#: the encoder's speed is the slope of its readings over this long, s
ENCODER_WINDOW_S = 0.2


@dataclass(frozen=True)
class BeltAxis:
    """The belt as installed, in the robot's base frame: where its upstream end's centre is (on the surface),
    which way objects travel (a horizontal unit vector), its length, width and nominal speed."""

    origin_m: Vec3
    direction: Vec3
    length_m: float
    width_m: float
    nominal_speed_m_s: float

    @property
    def surface_z_m(self) -> float:
        return float(self.origin_m[2])

    @property
    def across_direction(self) -> Vec3:
        """The horizontal unit vector across the belt (left of the direction of travel)."""
        return np.array([-self.direction[1], self.direction[0], 0.0])

    def along(self, point: Vec3) -> float:
        """How far downstream of the upstream end a point is, m."""
        return float(np.dot(np.asarray(point[:2]) - self.origin_m[:2], self.direction[:2]))

    def across(self, point: Vec3) -> float:
        return float(np.dot(np.asarray(point[:2]) - self.origin_m[:2], self.across_direction[:2]))

    def point(self, along_m: float, across_m: float, z_m: float) -> Vec3:
        p = self.origin_m + along_m * self.direction + across_m * self.across_direction
        return np.array([p[0], p[1], z_m])


@dataclass(frozen=True)
class Prediction:
    """Where the object will be at ``t_s`` (its centroid, base frame) moving at ``velocity_m_s``; ``sigma_m``
    and ``sigma_speed_m_s``: one-sigma errors along the belt."""

    t_s: float
    position_m: Vec3
    velocity_m_s: Vec3
    along_m: float
    sigma_m: float
    sigma_speed_m_s: float


@dataclass
class EncoderLog:
    """The belt's travel as its encoder reported it: (time s, travel m), oldest first, ``resolution_m`` a count.
    Shared by every track on the belt (a track may start on a frame taken before it existed)."""

    resolution_m: float = 0.0
    readings: deque[tuple[float, float]] = field(default_factory=lambda: deque(maxlen=6000))

    def add(self, t_s: float, travel_m: float) -> None:
        """One reading (readings come in time order; a second one at the same time is ignored)."""
        if self.readings and t_s <= self.readings[-1][0]:
            return
        self.readings.append((float(t_s), float(travel_m)))

    def travel_at(self, t_s: float) -> float:
        """E(t): interpolated between readings, carried on at the encoder's speed after the last."""
        times = [r[0] for r in self.readings]
        k = int(np.searchsorted(times, t_s))
        if k < len(times) and abs(times[k] - t_s) < 1e-9:
            return self.readings[k][1]
        if 0 < k < len(times):
            (t0, e0), (t1, e1) = self.readings[k - 1], self.readings[k]
            return e0 + (e1 - e0) * (t_s - t0) / (t1 - t0)
        if k == 0:
            t0, e0 = self.readings[0]
            return e0 + self.speed() * (t_s - t0)
        t1, e1 = self.readings[-1]
        return e1 + self.speed() * (t_s - t1)

    def speed(self) -> float:
        """The slope of the readings of the last :data:`ENCODER_WINDOW_S` (m/s)."""
        t_last, e_last = self.readings[-1]
        first = next(((t, e) for t, e in self.readings if t >= t_last - ENCODER_WINDOW_S), self.readings[0])
        return (e_last - first[1]) / (t_last - first[0]) if t_last - first[0] > 1e-6 else 0.0

    @property
    def usable(self) -> bool:
        return len(self.readings) >= 2 and self.readings[-1][0] - self.readings[0][0] > 1e-6


class BeltTrack:
    """One object on a belt: its motion model (module docstring) and what it looks like.

    ``add(t_s, detection)`` applies a detection of the frame taken at ``t_s``; ``encoder`` is the belt's encoder
    log (None: the belt has none), which its owner fills; ``predict(t_s)`` the model's answer. ``detection`` is the
    latest detection (its shape, for grasping), ``detections`` how many were applied."""

    def __init__(self, axis: BeltAxis, t_s: float, detection: Detection, encoder: EncoderLog | None = None,
                 measurement_sigma_m: float = MEASUREMENT_SIGMA_M) -> None:
        self.axis = axis
        self.sigma_z = float(measurement_sigma_m)
        self.detection = detection
        self.detections = 0
        self.last_time_s = float(t_s)
        self._across: list[float] = []
        self._z: list[float] = []
        self._offsets: list[tuple[float, float]] = []  # (frame time, position along the belt)
        self.encoder = encoder
        # the vision filter: state [s, v] at time self._t, covariance self._P
        speed = axis.nominal_speed_m_s
        self._t = float(t_s)
        self._x = np.array([axis.along(np.asarray(detection.centroid_base_m)), speed])
        prior_v = SPEED_PRIOR_SHARE * abs(speed) + SPEED_PRIOR_FLOOR_M_S
        self._P = np.diag([self.sigma_z**2, prior_v**2])
        self._first = True
        self.add(t_s, detection)

    # --- inputs ------------------------------------------------------------------------------------------------
    def add(self, t_s: float, detection: Detection) -> None:
        """One detection of the object in the frame taken at ``t_s`` (in time order)."""
        c = np.asarray(detection.centroid_base_m, dtype=float)
        z = self.axis.along(c)
        self.detection = detection
        self.detections += 1
        self.last_time_s = max(self.last_time_s, float(t_s))
        self._across.append(self.axis.across(c))
        self._z.append(float(c[2]))
        self._offsets.append((float(t_s), z))
        if self._first:  # the filter was started on this detection
            self._first = False
            return
        self._predict_filter(t_s)
        H = np.array([1.0, 0.0])
        S = float(H @ self._P @ H) + self.sigma_z**2
        K = self._P @ H / S
        self._x = self._x + K * (z - float(self._x[0]))
        self._P = (np.eye(2) - np.outer(K, H)) @ self._P

    def _predict_filter(self, t_s: float) -> None:
        dt = float(t_s) - self._t
        if dt <= 0:
            return
        F = np.array([[1.0, dt], [0.0, 1.0]])
        q = ACCEL_NOISE_M_S2**2
        Q = q * np.array([[dt**3 / 3, dt**2 / 2], [dt**2 / 2, dt]])
        self._x = F @ self._x
        self._P = F @ self._P @ F.T + Q
        self._t = float(t_s)

    # --- what it knows -----------------------------------------------------------------------------------------
    def innovation_sigma_m(self, t_s: float) -> float:
        """How far a detection at ``t_s`` may plausibly lie from the prediction (1 sigma, along the belt)."""
        return float(np.hypot(self.predict(t_s).sigma_m, self.sigma_z))

    def predict(self, t_s: float) -> Prediction:
        if self.encoder is not None and self.encoder.usable:
            along, sigma, speed, sigma_v = self._with_encoder(t_s, self.encoder)
        else:
            along, sigma, speed, sigma_v = self._vision_only(t_s)
        across = float(np.mean(self._across))
        position = self.axis.point(along, across, float(np.mean(self._z)))
        return Prediction(float(t_s), position, speed * self.axis.direction, along, sigma, sigma_v)

    def _vision_only(self, t_s: float) -> tuple[float, float, float, float]:
        dt = float(t_s) - self._t
        F = np.array([[1.0, dt], [0.0, 1.0]])
        q = ACCEL_NOISE_M_S2**2
        Q = q * np.array([[abs(dt)**3 / 3, dt**2 / 2], [dt**2 / 2, abs(dt)]])
        x = F @ self._x
        P = F @ self._P @ F.T + Q
        return float(x[0]), float(np.sqrt(P[0, 0])), float(x[1]), float(np.sqrt(P[1, 1]))

    def _with_encoder(self, t_s: float, enc: EncoderLog) -> tuple[float, float, float, float]:
        offsets = np.array([z - enc.travel_at(t) for t, z in self._offsets])
        s0 = float(np.mean(offsets))
        n = len(offsets)
        t_last = enc.readings[-1][0]
        speed = enc.speed()
        # the offset's error, the encoder's quantisation, and its speed's error over the time carried past the
        # last reading (the speed from two readings a window apart, each off by up to half a count)
        sigma_v = enc.resolution_m / ENCODER_WINDOW_S
        ahead = max(0.0, float(t_s) - t_last)
        sigma = float(np.sqrt(self.sigma_z**2 / n + enc.resolution_m**2 + (sigma_v * ahead)**2))
        return s0 + enc.travel_at(t_s), sigma, speed, sigma_v

    @property
    def across_m(self) -> float:
        return float(np.mean(self._across))
