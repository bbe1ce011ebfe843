// Opens a Foxglove Studio URL in headless chromium (puppeteer-core) and writes what it shows as JSON:
// the Problems list, topics, the 3D panel's frames, whether the image and 3D panels drew something.
// Usage: node probe.cjs --url URL --out OUT.json --chromium PATH --profile DIR [--wait S] [--screenshot PNG]
//        [--dump-text] [--until 3d,image,state --max-wait S]
// --until: after the --wait seconds, keep looking (every 2 s, up to --max-wait seconds in all) until each named
// kind of panel has drawn (3d/image: a picture, by the same measure as studio_driver._drawn; state: coloured
// bars, as _coloured), so a slow machine gets the time it needs instead of a fixed sleep that assumes a speed;
// the --panel-shots pictures wait for the same condition again (shootPanels).
"use strict";
const fs = require("fs");
const puppeteer = require("puppeteer-core");

function arg(name, fallback) {
  const i = process.argv.indexOf("--" + name);
  return i >= 0 ? process.argv[i + 1] : fallback;
}
const sleep = (ms) => new Promise((r) => setTimeout(r, ms));

// The panels with a canvas (3D, image, State Transitions, ...): kind, title text and where they are.
async function findPanels(page) {
  return page.evaluate(() => {
    const out = [];
    for (const c of document.querySelectorAll("canvas")) {
      let el = c;
      while (el && ![...el.querySelectorAll("button")].some((b) => b.getAttribute("title") === "Close Window")) el = el.parentElement;
      if (!el) continue;
      const is3d = [...el.querySelectorAll("button")].some((b) => b.getAttribute("title") === "Switch to 2D camera");
      const r = c.getBoundingClientRect();
      if (r.width < 50 || r.height < 50) continue;
      const text = el.innerText.trim();
      const kind = is3d ? "3d" : text.startsWith("/camera/") ? "image" : text.startsWith("State Transitions") ? "state"
        : "other";
      out.push({ kind, text: el.innerText.slice(0, 200),
                 x: r.left, y: r.top, width: r.width, height: r.height });
    }
    return out;
  });
}

// Whether a panel's pixels show what studio_driver's checks look for: many distinct colours (a picture) for
// 3d/image, more than 2% strongly saturated pixels (OpenCV's HSV S > 120) for state. Measured in the page from
// a screenshot of the panel's rectangle.
async function panelDrawn(page, p) {
  const png = await page.screenshot({ clip: { x: p.x, y: p.y, width: p.width, height: p.height }, encoding: "base64" });
  return pngDrawn(page, png, p.kind);
}

async function pngDrawn(page, png, kind) {
  return page.evaluate(async (b64, kind) => {
    const img = new Image();
    img.src = "data:image/png;base64," + b64;
    await img.decode();
    const cv = document.createElement("canvas");
    cv.width = img.width; cv.height = img.height;
    const ctx = cv.getContext("2d");
    ctx.drawImage(img, 0, 0);
    const d = ctx.getImageData(0, 0, cv.width, cv.height).data;
    if (kind === "state") {
      let sat = 0;
      for (let i = 0; i < d.length; i += 4) {
        const mx = Math.max(d[i], d[i + 1], d[i + 2]), mn = Math.min(d[i], d[i + 1], d[i + 2]);
        if (mx > 0 && ((mx - mn) * 255) / mx > 120) sat++;
      }
      return sat / (d.length / 4) > 0.02;
    }
    const colours = new Set();
    for (let i = 0; i < d.length; i += 4) colours.add(((d[i] >> 3) << 10) | ((d[i + 1] >> 3) << 5) | (d[i + 2] >> 3));
    return colours.size > 200;
  }, png, kind);
}

async function waitUntilDrawn(page, kinds, deadline) {
  for (;;) {
    const panels = await findPanels(page);
    let missing = [];
    for (const kind of kinds) {
      const mine = panels.filter((p) => p.kind === kind);
      let ok = false;
      for (const p of mine) if (await panelDrawn(page, p)) { ok = true; break; }
      if (!ok) missing.push(kind);
    }
    if (missing.length === 0 || Date.now() > deadline) return missing;
    await sleep(2000);
  }
}

// The panels and their screenshots, taken when each kind in `kinds` has a panel whose screenshot is drawn (or at
// the deadline): the files written are the very pictures judged, so studio_driver's verdict on them cannot differ
// from the wait's. Studio may re-create a chart after the first wait (seen once in twelve suite runs: the three
// charts' ChartJSManagers were built a second time and the State Transitions shot held its rows without bars);
// a shot taken at a fixed moment after that is a race, so the shots wait for the same condition.
async function shootPanels(page, dir, kinds, deadline) {
  for (;;) {
    const panels = await findPanels(page);
    const shots = [];
    for (const p of panels) {
      shots.push(await page.screenshot({ clip: { x: p.x, y: p.y, width: p.width, height: p.height }, encoding: "base64" }));
    }
    const missing = [];
    for (const kind of kinds) {
      let ok = false;
      for (let i = 0; i < panels.length && !ok; i++) if (panels[i].kind === kind) ok = await pngDrawn(page, shots[i], kind);
      if (!ok) missing.push(kind);
    }
    if (missing.length === 0 || Date.now() > deadline) {
      panels.forEach((p, i) => {
        p.file = dir + "/panel" + i + "-" + p.kind + ".png";
        fs.writeFileSync(p.file, Buffer.from(shots[i], "base64"));
      });
      return { panels, missing };
    }
    await sleep(2000);
  }
}

// foxglove-sdk 0.30's WebSocket server speaks the Foxglove WebSocket protocol under its newer subprotocol name
// "foxglove.sdk.v1"; this Studio build (1.48, in a worker) asks only for "foxglove.websocket.v1". The bridge
// accepts the old name and passes every frame through unchanged to the server under the new one.
function startBridge(target) {
  const WebSocket = require("ws");
  const server = new WebSocket.Server({ host: "127.0.0.1", port: 0, handleProtocols: (protocols) => [...protocols][0] });
  server.on("connection", (client) => {
    const upstream = new WebSocket(target, ["foxglove.sdk.v1"]);
    const pending = [];
    upstream.on("open", () => { for (const [d, b] of pending) upstream.send(d, { binary: b }); pending.length = 0; });
    upstream.on("message", (data, isBinary) => client.readyState === 1 && client.send(data, { binary: isBinary }));
    client.on("message", (data, isBinary) => upstream.readyState === 1 ? upstream.send(data, { binary: isBinary }) : pending.push([data, isBinary]));
    upstream.on("close", () => client.close());
    client.on("close", () => upstream.close());
    upstream.on("error", () => client.close());
    client.on("error", () => upstream.close());
  });
  return new Promise((resolve) => server.on("listening", () => resolve(server)));
}

async function main() {
  let url = arg("url");
  const bridgeTarget = arg("ws-bridge");
  let bridge = null;
  if (bridgeTarget) {
    bridge = await startBridge(bridgeTarget);
    url = url.replace("__BRIDGE__", encodeURIComponent("ws://127.0.0.1:" + bridge.address().port));
  }
  const out = arg("out");
  const waitS = Number(arg("wait", "25"));
  const browser = await puppeteer.launch({
    executablePath: arg("chromium"),
    headless: true,
    args: ["--headless", "--no-sandbox", "--disable-gpu", "--disable-background-networking",
      "--disable-component-update", "--disable-sync", "--no-first-run", "--use-angle=swiftshader",
      "--enable-unsafe-swiftshader", "--user-data-dir=" + arg("profile"), "--window-size=1600,1000"],
    defaultViewport: { width: 1600, height: 1000 },
    protocolTimeout: 180000,
  });
  const result = { errors: [], console: [] };
  try {
    const page = await browser.newPage();
    page.on("console", (m) => { if (result.console.length < 400) result.console.push(m.type() + ": " + m.text()); });
    page.on("pageerror", (e) => result.errors.push(String(e)));
    result.requests = [];
    page.on("request", (r) => result.requests.push(r.url().slice(0, 120)));
    const started = Date.now();
    await page.goto(url, { waitUntil: "load", timeout: 180000 });
    await sleep(waitS * 1000);
    const until = arg("until", "");
    if (until) {
      const maxWaitS = Number(arg("max-wait", "120"));
      result.notDrawnAtDeadline = await waitUntilDrawn(page, until.split(","), started + maxWaitS * 1000);
      result.waitedS = (Date.now() - started) / 1000;
    }
    if (process.argv.includes("--page")) {  // a plain page (the run report): its text and a full screenshot
      result.text = await page.evaluate(() => document.body.innerText);
      result.images = await page.evaluate(() => [...document.images].map((i) => [i.naturalWidth, i.naturalHeight]));
      const shot = arg("screenshot");
      if (shot) await page.screenshot({ path: shot, fullPage: true });
      return;
    }
    result.text = await page.evaluate(() => document.body.innerText);
    // the Problems tab of the data-source sidebar: its badge counts problems, its list names them
    Object.assign(result, await page.evaluate(async () => {
      const tab = [...document.querySelectorAll("button, [role=tab]")].find((e) => /^Problems/.test(e.innerText.trim()));
      if (!tab) return { problemsTab: false, problems: [] };
      tab.click();
      await new Promise((r) => setTimeout(r, 1500));
      const top = tab.getBoundingClientRect().bottom;
      const right = tab.parentElement.getBoundingClientRect().right + 40;
      const items = [...document.querySelectorAll("button, [role=button], li")].filter((e) => {
        const r = e.getBoundingClientRect();
        return r.top >= top && r.right <= right && r.width > 0 && e.innerText.trim().length > 0;
      }).map((e) => e.innerText.trim());
      const badge = tab.innerText.replace("Problems", "").trim();
      return { problemsTab: true, problemCount: badge ? Number(badge) : 0, problems: [...new Set(items)] };
    }));
    // where the 3D and image panels are, and (with --panel-shots) each one's picture, taken once the --until
    // kinds have drawn again (up to --max-wait seconds from now)
    const shotDir = arg("panel-shots");
    let panels;
    if (shotDir) {
      const kinds = until ? until.split(",") : [];
      const shotStart = Date.now();
      const shot = await shootPanels(page, shotDir, kinds, shotStart + Number(arg("max-wait", "120")) * 1000);
      panels = shot.panels;
      result.notDrawnAtShots = shot.missing;
      result.shotWaitS = (Date.now() - shotStart) / 1000;
    } else {
      panels = await findPanels(page);
    }
    result.panels = panels;
    const shot = arg("screenshot");
    if (shot) await page.screenshot({ path: shot });
    // the 3D panel's settings: select the panel, open "Panel settings", expand "Transforms": the frames it knows
    const three = panels.find((p) => p.kind === "3d");
    result.frames = [];
    if (three) {
      await page.mouse.click(three.x + three.width / 2, three.y + three.height / 2);
      await sleep(500);
      result.settingsText = await page.evaluate(async () => {
        const sleep = (ms) => new Promise((r) => setTimeout(r, ms));
        const nav = [...document.querySelectorAll("button")].find((b) => b.getAttribute("title") === "Panel settings");
        if (nav) { nav.click(); await sleep(1500); }
        const tf = [...document.querySelectorAll("div, span, p")].find((e) => e.children.length === 0 && /^Transforms( \(\d+\))?$/.test((e.innerText || "").trim()));
        if (tf) { tf.click(); await sleep(1500); }
        return document.body.innerText;
      });
      const m = result.settingsText.split("\n");
      const i0 = m.findIndex((l) => /^Transforms/.test(l.trim()));
      if (i0 >= 0) {
        for (let i = i0 + 1; i < m.length; i++) {
          const l = m[i].trim();
          if (/^(Topics|Custom Layers|Publish)/.test(l)) break;
          if (l && l !== "Settings") result.frames.push(l);
        }
      }
    }
  } finally {
    await browser.close();
    if (bridge) bridge.close();
    fs.writeFileSync(out, JSON.stringify(result, null, 1));
  }
}
main().catch((e) => { console.error(e); process.exit(1); });
