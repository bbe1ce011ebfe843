"""Drive a real Foxglove Studio (the open-source web build 1.48) in headless Chromium from tests.

`StudioServer` serves the studio bundle, a boot page, an optional layout and a folder of logs over HTTP
(with range requests, which Foxglove's remote-file source needs) on 127.0.0.1. `open_in_studio` starts
`probe.cjs` (puppeteer-core driving Debian's chromium) on a Foxglove URL and returns what it found: the
Problems list, the topics, the frames the 3D panel knows, whether the image panel drew, console errors.
`missing_reason()` says why the browser tests must skip on this machine (None when they can run).
"""

from __future__ import annotations

import http.server
import json
import os
import re
import shutil
import subprocess
import threading
import urllib.parse
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, ClassVar

ROOT = Path(__file__).resolve().parents[2]
CACHE = Path(os.environ.get("BT_GRASP_BROWSER_CACHE", ROOT / ".cache" / "browser"))
STUDIO = CACHE / "studio-1.48.0" / "package"
HERE = Path(__file__).resolve().parent
PROBE = HERE / "probe.cjs"


def chromium_path() -> str | None:
    for name in ("chromium", "chromium-browser", "google-chrome"):
        found = shutil.which(name)
        if found:
            return found
    return None


def missing_reason() -> str | None:
    """Why Foxglove cannot be driven here (None if it can). `make test` installs all of these."""
    if chromium_path() is None:
        return "chromium is not installed (tools/setup_browser.sh installs Debian's chromium)"
    if shutil.which("node") is None or shutil.which("npm") is None:
        return "node/npm are not installed"
    if not (STUDIO / "assets" / "index.js").is_file():
        return f"the Foxglove Studio web build is missing under {STUDIO} (run tools/setup_browser.sh)"
    if not (CACHE / "node_modules" / "puppeteer-core" / "package.json").is_file():
        return f"puppeteer-core is missing under {CACHE} (run tools/setup_browser.sh)"
    return None


_RANGE = re.compile(r"bytes=(\d*)-(\d*)$")


class _Handler(http.server.BaseHTTPRequestHandler):
    routes: ClassVar[dict[str, Path]] = {}

    def log_message(self, format: str, *args: Any) -> None:  # quiet
        return None

    def _resolve(self) -> Path | None:
        path = urllib.parse.unquote(urllib.parse.urlparse(self.path).path)
        for prefix, base in sorted(self.routes.items(), key=lambda kv: -len(kv[0])):
            if prefix.endswith("/") and path.startswith(prefix):
                target = (base / path[len(prefix):]).resolve()
                if base.resolve() in target.parents or target == base.resolve():
                    return target if target.is_file() else None
            elif path == prefix:
                return base if base.is_file() else None
        return None

    def do_HEAD(self) -> None:
        self._serve(head=True)

    def do_GET(self) -> None:
        self._serve(head=False)

    def _serve(self, head: bool) -> None:
        target = self._resolve()
        if target is None:
            self.send_error(404)
            return
        size = target.stat().st_size
        start, end = 0, size - 1
        status = 200
        match = _RANGE.match(self.headers.get("Range", ""))
        if match:
            a, b = match.groups()
            if a:
                start = int(a)
                end = min(int(b), size - 1) if b else size - 1
            elif b:
                start, end = max(0, size - int(b)), size - 1
            if start > end or start >= size:
                self.send_response(416)
                self.send_header("Content-Range", f"bytes */{size}")
                self.end_headers()
                return
            status = 206
        types = {".js": "application/javascript", ".html": "text/html", ".json": "application/json",
                 ".wasm": "application/wasm", ".png": "image/png", ".ttf": "font/ttf", ".css": "text/css"}
        self.send_response(status)
        self.send_header("Content-Type", types.get(target.suffix, "application/octet-stream"))
        self.send_header("Accept-Ranges", "bytes")
        self.send_header("Access-Control-Allow-Origin", "*")
        self.send_header("Access-Control-Expose-Headers", "Accept-Ranges, Content-Range, Content-Length")
        self.send_header("Cache-Control", "no-store")
        self.send_header("Content-Length", str(end - start + 1))
        if status == 206:
            self.send_header("Content-Range", f"bytes {start}-{end}/{size}")
        self.end_headers()
        if head:
            return
        try:
            with target.open("rb") as f:
                f.seek(start)
                remaining = end - start + 1
                while remaining > 0:
                    chunk = f.read(min(1 << 20, remaining))
                    if not chunk:
                        break
                    self.wfile.write(chunk)
                    remaining -= len(chunk)
        except (BrokenPipeError, ConnectionResetError):
            pass


class StudioServer:
    """Serves Foxglove Studio and a folder of logs on 127.0.0.1 (an OS-chosen port) in a thread."""

    def __init__(self, data_dir: Path, layout: Path | None = None) -> None:
        routes = {
            "/studio/": STUDIO,
            "/node_modules/": CACHE / "node_modules",
            "/data/": data_dir,
            "/studio.html": HERE / "studio.html",
            "/boot.js": HERE / "boot.js",
        }
        if layout is not None:
            routes["/layout.json"] = layout
        self.layout_param = "&layoutId=bt-grasp" if layout is not None else ""
        handler = type("Handler", (_Handler,), {"routes": routes})
        self.httpd = http.server.ThreadingHTTPServer(("127.0.0.1", 0), handler)
        self.port = self.httpd.server_address[1]
        self.thread = threading.Thread(target=self.httpd.serve_forever, daemon=True)

    def __enter__(self) -> StudioServer:
        self.thread.start()
        return self

    def __exit__(self, *exc: object) -> None:
        self.httpd.shutdown()
        self.httpd.server_close()

    def url_for_file(self, name: str) -> str:
        data = f"http://127.0.0.1:{self.port}/data/{urllib.parse.quote(name)}"
        return (f"http://127.0.0.1:{self.port}/studio.html?ds=remote-file&ds.url={urllib.parse.quote(data, safe='')}"
                f"{self.layout_param}")

    def url_for_websocket(self) -> str:
        """Studio on a live server, through the probe's protocol bridge (``open_in_studio(ws_bridge=...)``)."""
        return f"http://127.0.0.1:{self.port}/studio.html?ds=foxglove-websocket&ds.url=__BRIDGE__{self.layout_param}"


@dataclass
class StudioReport:
    """What the probe saw in Foxglove Studio."""

    problems: list[str] = field(default_factory=list)
    problem_count: int = 0
    frames: list[str] = field(default_factory=list)
    image_drawn: bool = False
    three_d_drawn: bool = False
    state_transitions_drawn: bool = False
    errors: list[str] = field(default_factory=list)
    raw: dict[str, Any] = field(default_factory=dict)


def open_in_studio(url: str, workdir: Path, *, wait_s: float = 25.0, screenshot: Path | None = None,
                   timeout_s: float = 240.0, ws_bridge: str | None = None,
                   until: tuple[str, ...] = (), max_wait_s: float = 120.0) -> StudioReport:
    """Open ``url`` in headless chromium, let Foxglove load, and report what it shows.

    ``wait_s`` is waited in any case; with ``until`` (panel kinds: "3d", "image", "state") the probe then goes on
    looking until each of them has drawn, up to ``max_wait_s`` from the page's start: a condition, not a sleep
    that assumes the machine's speed (a loaded machine's Studio took longer than 25 s to draw a live run)."""
    out = workdir / "probe.json"
    profile = workdir / "chromium-profile"
    profile.mkdir(parents=True, exist_ok=True)
    cmd = ["node", str(PROBE), "--url", url, "--out", str(out), "--chromium", str(chromium_path()),
           "--profile", str(profile), "--wait", str(wait_s)]
    if screenshot is not None:
        cmd += ["--screenshot", str(screenshot)]
    if ws_bridge is not None:
        cmd += ["--ws-bridge", ws_bridge]
    if until:
        cmd += ["--until", ",".join(until), "--max-wait", str(max_wait_s)]
    shots = workdir / "panels"
    shots.mkdir(exist_ok=True)
    cmd += ["--panel-shots", str(shots)]
    env = {**os.environ, "NODE_PATH": str(CACHE / "node_modules")}
    proc = subprocess.run(cmd, capture_output=True, text=True, timeout=timeout_s, env=env, cwd=CACHE)
    if proc.returncode != 0 or not out.is_file():
        raise RuntimeError(
            f"the Foxglove probe failed ({proc.returncode}):\n{proc.stdout[-3000:]}\n{proc.stderr[-3000:]}")
    raw = json.loads(out.read_text())
    if not raw.get("problemsTab"):
        raise RuntimeError(f"Foxglove showed no Problems tab; page text:\n{raw.get('text', '')[:2000]}")
    panels = raw.get("panels", [])
    return StudioReport(
        problems=[p for p in raw.get("problems", []) if p != "No problems found"],
        problem_count=int(raw.get("problemCount", 0)),
        frames=raw.get("frames", []),
        image_drawn=any(_drawn(Path(p["file"])) for p in panels if p["kind"] == "image" and "file" in p),
        three_d_drawn=any(_drawn(Path(p["file"])) for p in panels if p["kind"] == "3d" and "file" in p),
        state_transitions_drawn=any(_coloured(Path(p["file"])) for p in panels if p["kind"] == "state" and "file" in p),
        errors=raw.get("errors", []),
        raw=raw,
    )


def _coloured(png: Path) -> bool:
    """True when a panel's screenshot holds saturated colour (the State Transitions bars), not just text."""
    import cv2
    import numpy as np

    img = cv2.imread(str(png))
    if img is None:
        return False
    hsv = cv2.cvtColor(img, cv2.COLOR_BGR2HSV)
    return float(np.mean(hsv[:, :, 1] > 120)) > 0.02


def _drawn(png: Path) -> bool:
    """True when a panel's screenshot holds a picture (many distinct colours), not a flat background."""
    import cv2
    import numpy as np

    img = cv2.imread(str(png))
    if img is None:
        return False
    colours = np.unique((img // 8).reshape(-1, 3), axis=0)
    return len(colours) > 200


def render_page(url: str, workdir: Path, screenshot: Path, *, wait_s: float = 2.0,
                timeout_s: float = 120.0) -> dict[str, Any]:
    """Open a plain page (e.g. ``file:///.../report.html``) in headless chromium: its text, its images' sizes,
    every URL it requested, and a full-page screenshot."""
    out = workdir / "page.json"
    profile = workdir / "chromium-profile"
    profile.mkdir(parents=True, exist_ok=True)
    cmd = ["node", str(PROBE), "--page", "--url", url, "--out", str(out), "--chromium", str(chromium_path()),
           "--profile", str(profile), "--wait", str(wait_s), "--screenshot", str(screenshot)]
    env = {**os.environ, "NODE_PATH": str(CACHE / "node_modules")}
    proc = subprocess.run(cmd, capture_output=True, text=True, timeout=timeout_s, env=env, cwd=CACHE)
    if proc.returncode != 0 or not out.is_file():
        raise RuntimeError(f"the page probe failed ({proc.returncode}):\n{proc.stdout[-3000:]}\n{proc.stderr[-3000:]}")
    result: dict[str, Any] = json.loads(out.read_text())
    return result


def skip_without_browser() -> None:
    """Skip the calling test, saying why, where chromium, npm or the Studio build is missing."""
    import pytest

    reason = missing_reason()
    if reason is not None:
        print(f"SKIPPED (browser): {reason}")
        pytest.skip(reason)


#: every link of the robot description a viewer must know
ROBOT_LINKS = ("base_link", "shoulder_link", "upper_arm_link", "forearm_link", "wrist_1_link", "wrist_2_link",
               "wrist_3_link", "gripper_palm", "left_finger", "right_finger", "tcp")


@contextmanager
def serving(data_dir: Path, layout: Path | None = None) -> Iterator[StudioServer]:
    with StudioServer(data_dir, layout) as server:
        yield server
