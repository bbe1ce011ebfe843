"""Opening a RealSense source: a recording file, or a live device by serial number (or the only one connected).

Every refusal is one sentence naming the file or the device and the problem (:class:`DeviceError`,
:class:`bt_grasp.hardware.recording_file.RecordingError`), exit code 2; nothing streams before every check passed.
"""

from __future__ import annotations

import json
import logging
from pathlib import Path

from bt_grasp.errors import InputError
from bt_grasp.files.bounded_io import read_user_file
from bt_grasp.hardware.device_objects import RsObject
from bt_grasp.hardware.realsense_camera import COLOR_FORMATS, RealSenseCamera
from bt_grasp.hardware.realsense_lib import pyrealsense2
from bt_grasp.hardware.realsense_settings import RealSenseSettings
from bt_grasp.hardware.recording_file import RecordingError, check_recording, library_problem
from bt_grasp.interfaces import Mount

log = logging.getLogger(__name__)

#: a RealSense Viewer preset is a small JSON file (Intel's shipped presets are 2-5 KB)
MAX_PRESET_BYTES = 1 << 20
SETUP_HINT = "check the USB 3 cable and the udev rules (docs/real-camera.md)"


class DeviceError(InputError):
    """A live device that cannot be used as asked (none connected, another serial number, a refused mode)."""


def open_recording(path: str | Path, settings: RealSenseSettings = RealSenseSettings(),
                   mount: Mount = Mount.EYE_TO_HAND) -> RealSenseCamera:
    """A recording (``.db3``, or a ROS 1 ``.bag``) played through pyrealsense2's pipeline, every frame in order
    (not in real time); its end is a dropped frame. One sentence and exit 2 for a file it cannot play."""
    path = Path(path)
    check_recording(path)
    rs = pyrealsense2("reading a RealSense recording")
    pipeline, config = rs.pipeline(), rs.config()
    try:
        config.enable_device_from_file(str(path), repeat_playback=False)
        # not in real time, set on the device the pipeline will start, before it starts: a pipeline started in
        # real time drops the frames that arrive before both sensors stream (often the first pair)
        resolved = config.resolve(rs.pipeline_wrapper(pipeline))
        device = resolved.get_device().as_playback()
        device.set_real_time(False)
        # paused until both sensors stream: librealsense's playback starts reading the file when the first of its
        # sensors starts and drops what it reads for a sensor not yet started, and it takes each start on its reading
        # thread after pipeline.start returned (its status reads "stopped" until then). resume() returns once the
        # reading thread took both starts, so from here "stopped" means the file ended. A 1-frame household
        # recording lost its only pair once in CI (never in 1,000 tries here, loaded or not).
        device.pause()
        profile = pipeline.start(config)
        playback = profile.get_device().as_playback()
        playback.resume()
    except RuntimeError as exc:
        raise library_problem(path, exc) from None
    kinds = {str(s.stream_type()) for s in profile.get_streams()}
    missing = [name for name, kind in (("depth", rs.stream.depth), ("colour", rs.stream.color))
               if str(kind) not in kinds]
    if missing:
        pipeline.stop()
        raise RecordingError(path, f"holds no {' and no '.join(missing)} stream (bt_grasp needs both)")
    _check_color_format(rs, profile, path, pipeline)
    return RealSenseCamera(rs, pipeline, profile, settings, mount, str(path), playback=playback)


def _check_color_format(rs: RsObject, profile: RsObject, source: str | Path, pipeline: RsObject) -> None:
    fmt = str(profile.get_stream(rs.stream.color).format()).removeprefix("format.")
    if fmt not in COLOR_FORMATS:
        pipeline.stop()
        raise RecordingError(source, f"streams colour as {fmt}; bt_grasp reads {', '.join(COLOR_FORMATS)}")


def choose_device(context: RsObject, serial: str | None) -> RsObject:
    """The device with ``serial`` (or the only one when None) among ``context``'s; DeviceError otherwise."""
    rs = pyrealsense2("a live RealSense camera")
    devices = list(context.query_devices())
    serials = [str(d.get_info(rs.camera_info.serial_number)) if d.supports(rs.camera_info.serial_number) else ""
               for d in devices]
    if not devices:
        raise DeviceError("--device", f"no RealSense device is connected; {SETUP_HINT}")
    if serial:
        if serial not in serials:
            raise DeviceError("--device", f"no RealSense device with serial number {serial} is connected "
                              f"(connected: {', '.join(sorted(serials))})")
        return devices[serials.index(serial)]
    if len(devices) > 1:
        raise DeviceError("--device", f"{len(devices)} RealSense devices are connected ({', '.join(sorted(serials))}); "
                          "name one: --device SERIAL")
    return devices[0]


def read_preset(path: str | Path) -> str:
    """A RealSense Viewer preset's text: a JSON object, read bounded; InputError (one sentence) otherwise."""
    data = read_user_file(path, MAX_PRESET_BYTES)
    try:
        value = json.loads(data.decode("utf-8"))
    except (UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise InputError(path, f"is not a RealSense Viewer preset (JSON): {exc}") from None
    if not isinstance(value, dict) or not value:
        raise InputError(path, "is not a RealSense Viewer preset (a JSON object of settings)")
    return data.decode("utf-8")


def load_preset(device: RsObject, serial: str, path: str | Path) -> None:
    """Load a Viewer preset into the device's D400 advanced mode (the Viewer's own call); DeviceError when the device
    has no advanced mode, has it turned off, or refuses the preset."""
    rs = pyrealsense2("a RealSense Viewer preset")
    text = read_preset(path)
    try:
        advanced = rs.rs400_advanced_mode(device)
        enabled = advanced.is_enabled()
    except RuntimeError:
        raise DeviceError("--preset", f"the device {serial} takes no RealSense Viewer preset (it has no D400 "
                          "advanced mode)") from None
    if not enabled:
        raise DeviceError("--preset", f"the device {serial} has its advanced mode turned off; turn it on in the "
                          "RealSense Viewer (the device restarts) and try again")
    try:
        advanced.load_json(text)
    except RuntimeError as exc:
        raise DeviceError("--preset", f"the device {serial} refused the preset {path}: {exc}") from None
    log.info("loaded the preset %s into %s", path, serial)


def start_device(context: RsObject, serial: str | None, settings: RealSenseSettings,
                 record_to: Path | None = None) -> tuple[RsObject, RsObject, RsObject, str]:
    """Choose the device, load the preset, start the pipeline on it with the settings' streams (and the library's
    recorder when ``record_to``): (pipeline, profile, device, serial)."""
    rs = pyrealsense2("a live RealSense camera")
    device = choose_device(context, serial)
    chosen = str(device.get_info(rs.camera_info.serial_number))
    if device.supports(rs.camera_info.usb_type_descriptor):
        usb = str(device.get_info(rs.camera_info.usb_type_descriptor))
        if usb.startswith("2"):
            log.warning("the device %s is on USB %s: a D435 needs USB 3 for full frame rates", chosen, usb)
    if settings.preset is not None:
        load_preset(device, chosen, settings.preset)
    w, h, fps = settings.width_px, settings.height_px, settings.fps
    config = rs.config()
    config.enable_device(chosen)
    config.enable_stream(rs.stream.depth, w, h, rs.format.z16, fps)
    config.enable_stream(rs.stream.color, w, h, rs.format.rgb8, fps)
    if record_to is not None:
        config.enable_record_to_file(str(record_to))
    pipeline = rs.pipeline(context)
    try:
        profile = pipeline.start(config)
    except RuntimeError as exc:
        raise DeviceError("--device", f"the device {chosen} cannot stream depth and RGB colour at {w}x{h}, "
                          f"{fps} fps: {exc}") from None
    return pipeline, profile, device, chosen


def open_device(serial: str | None = None, settings: RealSenseSettings = RealSenseSettings(),
                mount: Mount = Mount.EYE_TO_HAND, context: RsObject = None) -> RealSenseCamera:
    """A live device (``serial``, or the only one connected) streaming the settings' depth and colour, its
    auto-exposure settling frames skipped. ``context``: the pyrealsense2 context to find it in (default: a new
    one, which lists the USB devices)."""
    rs = pyrealsense2("a live RealSense camera")
    context = context if context is not None else rs.context()
    pipeline, profile, _device, chosen = start_device(context, serial, settings)
    camera = RealSenseCamera(rs, pipeline, profile, settings, mount, f"RealSense {chosen}")
    if settings.settle_frames:
        came = camera.skip(settings.settle_frames)
        log.info("%s: skipped %d of %d settling frames", camera.source, came, settings.settle_frames)
    return camera
