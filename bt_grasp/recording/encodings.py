"""Message encodings that give the same bytes in either process: the recorder's or its writer process's.

A recorder that writes its file through a writer process (``writer_process.py``) hands these messages over
as their inputs, and the child encodes them on the other core; a recorder that also feeds a live viewer (or
writes the file itself) encodes them in-process with the same function. Each is one function of plain
inputs (numbers, strings, lists, dicts, numpy arrays), so where it runs cannot change a byte of the log.
"""

from __future__ import annotations

import enum
import json
from collections.abc import Callable

import numpy as np
from numpy.typing import NDArray

from bt_grasp.recording import schemas
from bt_grasp.recording.jsonable import to_jsonable

_JSON = json.JSONEncoder(separators=(",", ":"), allow_nan=False)


class Encoding(enum.Enum):
    """What turns a handed-over message's inputs into its bytes (see :func:`encode`)."""

    JSON = "json"  #: (obj,): compact JSON
    TRAJECTORY = "trajectory"  #: (name, kind, times_s, q_rad): /motion/trajectory's JSON
    COLOR = "color"  #: (log_time_ns, rgb, frame_id, format, jpeg_quality): a foxglove.CompressedImage
    DEPTH = "depth"  #: (log_time_ns, depth_m, frame_id, encoding): a foxglove.RawImage


def dumps(obj: object) -> bytes:
    """Compact JSON; NaN and infinities raise ``ValueError`` (the log's JSON has none)."""
    return _JSON.encode(obj).encode()


def json_bytes(obj: object) -> bytes:
    """Compact JSON of ``obj``; a value JSON cannot hold (NaN, an object) is first made JSON-able by the log's
    rules (``to_jsonable``), so a message never fails to encode in a writer process, where no caller would
    see the error."""
    try:
        return dumps(obj)
    except (ValueError, TypeError):
        return dumps(to_jsonable(obj, max_array_elements=1 << 30))


def trajectory_bytes(name: str, kind: str, times_s: NDArray[np.float64], q_rad: NDArray[np.float64]) -> bytes:
    """/motion/trajectory: the trajectory's name and kind, its times and one point per time."""
    times = np.asarray(times_s, dtype=np.float64).ravel()
    q = np.asarray(q_rad, dtype=np.float64).reshape(times.size, -1)
    t_list = times.tolist()
    msg = {"name": name, "kind": kind, "times_s": t_list,
           "points": [{"t_s": t, "q_rad": row} for t, row in zip(t_list, q.tolist(), strict=True)]}
    return json_bytes(msg)


def color_bytes(log_time_ns: int, rgb: NDArray[np.uint8], frame_id: str, fmt: str, jpeg_quality: int) -> bytes:
    data: bytes = schemas.compressed_image(log_time_ns, rgb, frame_id, fmt, jpeg_quality).SerializeToString()
    return data


def depth_bytes(log_time_ns: int, depth_m: NDArray[np.floating], frame_id: str, encoding: str) -> bytes:
    data: bytes = schemas.depth_image(log_time_ns, depth_m, frame_id, encoding).SerializeToString()
    return data


#: each encoding's function; the arguments differ from one to the next (the ``Encoding`` members say which)
_ENCODERS: dict[Encoding, Callable[..., bytes]] = {
    Encoding.JSON: json_bytes, Encoding.TRAJECTORY: trajectory_bytes, Encoding.COLOR: color_bytes,
    Encoding.DEPTH: depth_bytes,
}


def encode(encoding: Encoding, args: tuple[object, ...]) -> bytes:
    """The message's bytes from its inputs."""
    return _ENCODERS[encoding](*args)



