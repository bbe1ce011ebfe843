"""The fast /tf encoder writes what Foxglove's protobuf classes build, field for field."""

from __future__ import annotations

import numpy as np
from foxglove_schemas_protobuf.FrameTransforms_pb2 import FrameTransforms
from scipy.spatial.transform import Rotation

from bt_grasp.recording import schemas
from bt_grasp.recording.tf_encoding import FrameTransformsEncoder, quats_xyzw


def _random_transforms(n: int, seed: int) -> list[tuple[str, str, np.ndarray]]:
    rng = np.random.default_rng(seed)
    out = []
    for i in range(n):
        T = np.eye(4)
        T[:3, :3] = Rotation.random(random_state=int(rng.integers(1 << 30))).as_matrix()
        T[:3, 3] = rng.normal(size=3)
        out.append(("base_link", f"link_{i}", T))
    # the awkward rotations: identity, half turns about each axis
    for k, axis in enumerate(np.eye(3)):
        T = np.eye(4)
        T[:3, :3] = Rotation.from_rotvec(np.pi * axis).as_matrix()
        out.append(("world", f"flip_{k}", T))
    out.append(("world", "base_link", np.eye(4)))
    return out


def test_fast_tf_bytes_decode_to_the_same_message() -> None:
    transforms = _random_transforms(20, seed=1)
    stamp = 1_795_430_000_123_456_789
    fast = FrameTransforms()
    fast.ParseFromString(FrameTransformsEncoder().encode(stamp, transforms))
    slow = schemas.frame_transforms(stamp, transforms)
    assert len(fast.transforms) == len(slow.transforms) == len(transforms)
    for a, b in zip(fast.transforms, slow.transforms, strict=True):
        assert (a.parent_frame_id, a.child_frame_id) == (b.parent_frame_id, b.child_frame_id)
        assert (a.timestamp.seconds, a.timestamp.nanos) == (b.timestamp.seconds, b.timestamp.nanos)
        assert [a.translation.x, a.translation.y, a.translation.z] == [b.translation.x, b.translation.y,
                                                                      b.translation.z]
        qa = np.array([a.rotation.x, a.rotation.y, a.rotation.z, a.rotation.w])
        qb = np.array([b.rotation.x, b.rotation.y, b.rotation.z, b.rotation.w])
        assert min(np.abs(qa - qb).max(), np.abs(qa + qb).max()) < 1e-12  # q and -q are one rotation


def test_batch_quaternions_rebuild_the_matrices() -> None:
    R = np.stack([Rotation.random(random_state=i).as_matrix() for i in range(200)])
    q = quats_xyzw(R)
    assert np.allclose(Rotation.from_quat(q).as_matrix(), R, atol=1e-12)
