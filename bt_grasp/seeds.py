"""The run's seed path: every random draw of a run comes from one stream of the run's seed, named here.

A run has one seed (``--seed``, a campaign row's, ...). Each consumer of randomness gets its own stream of it,
so that drawing more in one place never changes what another draws: the objects' poses do not move when the
camera draws more noise, and a fault plan with one more fault leaves the grasps as they were. A stream is
``numpy.random.SeedSequence(seed, spawn_key=(stream,))``, which is exactly the n-th child of
``SeedSequence(seed).spawn(...)``: the world's first four streams are the ones it has always drawn from.

| stream | who draws from it |
| --- | --- |
| ``OBJECTS`` | the world: which objects a scene's draw keeps, their poses and rest orientations |
| ``CAMERA`` | the simulated D435's depth and colour noise |
| ``FAULTS`` | a fault plan's probabilistic triggers and random effects (one child per fault) |
| ``DEPTH_IMAGER`` | the simulated D435's depth imager, when its two pictures are drawn (``camera record``) |
| ``PLANNER`` | OMPL's searches and the planner's IK restarts (``PlannerOptions.seed``) |
| ``CALIBRATION`` | the hand-eye calibration's sampled board views |
| ``GRASPS`` | antipodal grasp sampling on an object's cloud |
| ``PERCEPTION`` | the table plane's RANSAC |
| ``IK`` | the random restarts of IK queries the leaves make themselves (a release pose, a servo step) |

The order is part of what makes a seed reproduce a run: streams are only ever appended, never reordered.
``docs/architecture.md`` ("The seed path") says how to add one.
"""

from __future__ import annotations

import enum
from dataclasses import dataclass

import numpy as np


class Stream(enum.IntEnum):
    """A consumer of a run's randomness; its value is its spawn key under the run's seed."""

    OBJECTS = 0
    CAMERA = 1
    FAULTS = 2
    DEPTH_IMAGER = 3
    PLANNER = 4
    CALIBRATION = 5
    GRASPS = 6
    PERCEPTION = 7
    IK = 8


#: the largest value :meth:`RunSeeds.integer` returns (libraries that take a 32-bit seed: OMPL)
MAX_INTEGER_SEED = 2**31 - 1


@dataclass(frozen=True)
class RunSeeds:
    """The streams of one run's seed."""

    seed: int

    def sequence(self, stream: Stream) -> np.random.SeedSequence:
        """The stream's seed sequence (spawn children of it for per-item streams, e.g. one per fault)."""
        return np.random.SeedSequence(int(self.seed), spawn_key=(int(stream),))

    def generator(self, stream: Stream) -> np.random.Generator:
        """A fresh generator on the stream: the same draws every time it is asked for."""
        return np.random.default_rng(self.sequence(stream))

    def integer(self, stream: Stream) -> int:
        """The stream as one integer in [1, MAX_INTEGER_SEED], for libraries that take an integer seed (OMPL
        reads 0 as "seed from the clock", so 0 is never returned)."""
        value = int(self.sequence(stream).generate_state(1, dtype=np.uint32)[0])
        return 1 + value % MAX_INTEGER_SEED
