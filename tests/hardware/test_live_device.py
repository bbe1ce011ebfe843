"""The live path on pyrealsense2 itself: software D435s added to a context (``add_to``) and fed from a thread, read
by ``open_device`` exactly as a USB D435 is (issue 39): choosing by serial number, frames that do not come are
dropped frames, auto-exposure settling frames are skipped, the post-processing filters run, presets are refused by a
device without a D400 advanced mode, and a live recording plays back."""

from __future__ import annotations

import dataclasses
import json
from pathlib import Path

import numpy as np
import pyrealsense2 as rs
import pytest
from rs_fixtures import PERIOD_NS, Feeder, picture, streams

from bt_grasp.errors import InputError
from bt_grasp.hardware.realsense_open import DeviceError, open_device, open_recording, read_preset
from bt_grasp.hardware.realsense_settings import DepthFilter, RealSenseSettings, parse_filters
from bt_grasp.hardware.software_d435 import SoftwareD435

FAST = RealSenseSettings(width_px=64, height_px=48, fps=30, timeout_ms=500, settle_frames=0)


def _context(*serials: str) -> tuple[rs.context, list[SoftwareD435]]:
    context = rs.context()
    devices = [SoftwareD435(streams(serial)) for serial in serials]
    for device in devices:
        device.add_to(context)
    return context, devices


def test_the_device_is_chosen_by_serial_number_and_an_ambiguous_or_unknown_one_is_one_sentence() -> None:
    context, devices = _context("111111111111", "222222222222")
    with Feeder(devices[1]), open_device("222222222222", FAST, context=context) as camera:
        assert camera.info.serial == "222222222222"
        frame = camera.capture()
        assert frame is not None and frame.color.shape == (48, 64, 3)
    with pytest.raises(DeviceError, match=r"2 RealSense devices are connected \(111111111111, 222222222222\); name"):
        open_device(None, FAST, context=context)
    with pytest.raises(DeviceError, match="no RealSense device with serial number 333 is connected"):
        open_device("333", FAST, context=context)
    with pytest.raises(DeviceError, match="no RealSense device is connected; check the USB 3 cable"):
        open_device(None, FAST, context=rs.context(json.dumps({"device-mask": 0})))


def test_a_frame_that_does_not_come_is_a_dropped_frame_and_stamps_are_the_devices() -> None:
    context, (device,) = _context("123456789012")
    feeder = Feeder(device)
    with feeder, open_device(None, FAST, context=context) as camera:
        frames = [camera.capture() for _ in range(3)]
        assert all(f is not None for f in frames)
        stamps = [f.stamp_ns for f in frames if f is not None]
        assert all(s % PERIOD_NS == 0 for s in stamps) and stamps == sorted(stamps)  # the pushed device times
        feeder.stop()
        while camera.capture() is not None:  # frames already in the pipeline's queue
            pass
        assert camera.capture() is None  # nothing more within the timeout: dropped, not an exception
        assert camera.dropped >= 2


def test_settling_frames_are_skipped_on_a_live_device() -> None:
    context, (device,) = _context("123456789012")
    settle = dataclasses.replace(FAST, settle_frames=5)
    with Feeder(device), open_device(None, settle, context=context) as camera:
        frame = camera.capture()
    assert frame is not None
    assert frame.stamp_ns >= 5 * PERIOD_NS  # frames 0-4 went to the auto exposure


def test_the_post_processing_filters_run_on_live_depth() -> None:
    context, (device,) = _context("123456789012")
    depth, color = picture(0)
    depth[20:24, 30:34] = 0.0  # a hole
    plain, filtered = [], []
    for settings, out in ((FAST, plain), (dataclasses.replace(FAST, filters=parse_filters("hole-filling,spatial")),
                                          filtered)):
        with open_device(None, settings, context=context) as camera:
            for k in range(3):
                device.push(depth, color, k * PERIOD_NS, k)
                frame = camera.capture()
                assert frame is not None
                out.append(frame.depth_m)
    hole = plain[-1] == 0
    assert hole.sum() >= 16  # the hole, aligned onto colour
    assert (filtered[-1][hole] > 0).all()  # filled
    valid = ~hole
    assert np.std(filtered[-1][valid]) < np.std(plain[-1][valid])  # smoothed
    assert parse_filters("temporal,spatial") == (DepthFilter.TEMPORAL, DepthFilter.SPATIAL)
    with pytest.raises(InputError, match="'median' is not a depth filter"):
        parse_filters("median")


def test_a_preset_is_checked_before_the_device_and_refused_by_one_without_advanced_mode(tmp_path: Path) -> None:
    preset = tmp_path / "HighAccuracy.json"
    preset.write_text(json.dumps({"parameters": {"controls-laserpower": "150"}}))
    assert "laserpower" in read_preset(preset)
    for bad, problem in ((b"\x89PNG", "is not a RealSense Viewer preset"), (b"[1, 2]", "a JSON object")):
        (tmp_path / "bad.json").write_bytes(bad)
        with pytest.raises(InputError, match=problem):
            read_preset(tmp_path / "bad.json")
    context, _devices = _context("123456789012")
    with pytest.raises(DeviceError, match="the device 123456789012 takes no RealSense Viewer preset"):
        open_device(None, dataclasses.replace(FAST, preset=preset), context=context)


def test_a_live_device_records_with_the_librarys_recorder_and_the_recording_plays_back(tmp_path: Path) -> None:
    from bt_grasp.hardware.live_record import record_device

    context, (device,) = _context("123456789012")
    out = tmp_path / "live.db3"
    with Feeder(device):
        done = record_device(out, 0.5, None, FAST, context=context)
    assert done.serial == "123456789012" and done.frame_sets >= 5
    with open_recording(out) as camera:
        assert camera.info.serial == "123456789012"
        count = 0
        while camera.capture() is not None:
            count += 1
    assert count >= 5
