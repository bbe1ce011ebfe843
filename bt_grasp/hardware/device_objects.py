"""The device libraries' objects, which come with no type information (pyrealsense2, ur_rtde): one name for each
library's values, so a signature says which library an untyped value belongs to."""

from __future__ import annotations

from typing import Any, TypeAlias

#: a pyrealsense2 value: the module itself, a context, device, pipeline, profile, frame, filter or option
RsObject: TypeAlias = Any
#: a ur_rtde value: an RTDE control or receive interface, or what one of their calls returns
RtdeObject: TypeAlias = Any
