"""Perception sees the fixtures' walls (a tray's rim, a bin) and whatever was already put in them; the robot
knows from the scene file (installation data) where the fixtures stand, so detections inside a fixture's
footprint are not objects to pick. Flat markers are kept: an object on a marker is still on the table; so
is a conveyor's belt (it brings the objects to pick)."""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from bt_grasp.perception.results import Detection, PerceptionResult, PerceptionStatus
from bt_grasp.scene.conveyor import Conveyor
from bt_grasp.scene.format import Scene

#: a detection whose centre lies this close outside a fixture's outer footprint still counts as the fixture
FIXTURE_MARGIN_M = 0.02


def inside_fixture(scene: Scene, xy_world: tuple[float, float]) -> str | None:
    """The name of the solid fixture whose footprint (plus the margin) holds a world point, or None."""
    for fixture in scene.fixtures:
        if isinstance(fixture, Conveyor):  # a belt carries the objects to pick: they are not "in" it
            continue
        parts = [p for p in fixture.parts() if p.solid]
        if not parts:
            continue
        for part in parts:
            local = np.linalg.inv(part.T_world_part) @ np.array([xy_world[0], xy_world[1], 0.0, 1.0])
            if abs(local[0]) <= part.size_m[0] / 2 + FIXTURE_MARGIN_M and \
                    abs(local[1]) <= part.size_m[1] / 2 + FIXTURE_MARGIN_M:
                return fixture.name
    return None


def without_fixtures(result: PerceptionResult, scene: Scene) -> PerceptionResult:
    """The perception result without detections inside a fixture (None when the scene has no fixtures)."""
    if not scene.fixtures or not result.ok:
        return result
    T_world_base = scene.T_world_base()

    def keep(det: Detection) -> bool:
        p = T_world_base @ np.array([*det.centroid_base_m, 1.0])
        return inside_fixture(scene, (float(p[0]), float(p[1]))) is None

    detections = tuple(d for d in result.detections if keep(d))
    others = tuple(d for d in result.others if keep(d))
    if len(detections) == len(result.detections) and len(others) == len(result.others):
        return result

    if not others:
        return replace(result, status=PerceptionStatus.NO_OBJECTS, detections=(), others=(),
                       message="only fixtures and what is in them are on the table")
    if not detections:
        return replace(result, status=PerceptionStatus.NO_MATCH, detections=(), others=others,
                       message="the only match is inside a fixture")
    return replace(result, detections=detections, others=others)
