"""The width and height a PNG or JPEG says it has, read from its header before anything is decoded.

A recorded colour image is a PNG or JPEG (``bt_grasp.recording.schemas``) of at most the camera's 4096 x 4096
pixels. A 2.6 MB PNG of zeros can say 30,000 x 30,000: decoding it took 5-8 GB and 90 s in `replay
--export-frames` and `--report` (found by the pre-review attack, from a 730 KB log). The reader asks for the size
here first and refuses what no camera of bt_grasp's makes.
"""

from __future__ import annotations

import io
import struct
import warnings

#: the largest picture side a scene's camera has (``bt_grasp.scene.format.Camera.width_px``' limit)
MAX_IMAGE_SIDE = 4096

_PNG = b"\x89PNG\r\n\x1a\n"
#: JPEG start-of-frame markers (baseline, extended, progressive, lossless, ...), which carry the size
_SOF = frozenset({0xC0, 0xC1, 0xC2, 0xC3, 0xC5, 0xC6, 0xC7, 0xC9, 0xCA, 0xCB, 0xCD, 0xCE, 0xCF})


def image_size(data: bytes) -> tuple[int, int] | None:
    """(width, height) from a PNG's IHDR or a JPEG's start-of-frame segment; None when ``data`` is neither or its
    header is cut."""
    if data.startswith(_PNG):
        if len(data) < 24 or data[12:16] != b"IHDR":
            return None
        width, height = struct.unpack(">II", data[16:24])
        return width, height
    if data.startswith(b"\xff\xd8"):
        pos = 2
        while pos + 4 <= len(data):
            if data[pos] != 0xFF:
                return None
            marker = data[pos + 1]
            if marker == 0xFF:  # fill byte
                pos += 1
                continue
            if marker in (0xD8, 0x01) or 0xD0 <= marker <= 0xD7:  # segments without a length
                pos += 2
                continue
            (length,) = struct.unpack(">H", data[pos + 2:pos + 4])
            if marker in _SOF:
                if pos + 9 > len(data):
                    return None
                height, width = struct.unpack(">HH", data[pos + 5:pos + 9])
                return width, height
            if length < 2:
                return None
            pos += 2 + length
    return None


#: the largest side of a picture a mesh's material names (a texture): the renderer's own textures are at most
#: 4096 a side, and a 20000 x 20000 PNG of 431 KB took 5.3 GB once decoded
MAX_TEXTURE_SIDE = 4096


def picture_size(data: bytes) -> tuple[int, int] | None:
    """(width, height) of a picture in any format Pillow reads, from its header only: PNG and JPEG by
    :func:`image_size`, other formats by Pillow's lazy ``Image.open``, which reads the header and decodes nothing
    (its own decompression-bomb guard refuses a picture of over twice ``Image.MAX_IMAGE_PIXELS``: None then, as
    for anything that is not a picture)."""
    size = image_size(data)
    if size is not None:
        return size
    from PIL import Image  # deferred: Pillow is imported only when a picture is not a PNG or JPEG

    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # Pillow's DecompressionBombWarning: the caller refuses by the size
            with Image.open(io.BytesIO(data)) as image:
                return int(image.size[0]), int(image.size[1])
    except Exception:  # any reader's failure on a picture that is not one (or is a bomb Pillow refuses)
        return None
