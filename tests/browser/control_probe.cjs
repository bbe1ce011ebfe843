// Drives a live bt_grasp run from Foxglove Studio's stock panels (the control layout's Parameters panel and
// Publish buttons) in headless chromium, the way an operator would: reads a parameter's value from the panel's
// table, types a new value into its editor and presses "Submit change", presses a Publish button, reads the
// Problems list. Steps come from a JSON file; what each step saw is written to --out.
// Usage: node control_probe.cjs --url URL --ws-bridge WS --steps STEPS.json --out OUT.json --chromium PATH
//        --profile DIR
// Steps: {op: "wait", name, until: {eq|gt|ne|has: V}, timeout}   until the panel shows such a value
//        {op: "set", name, text}                                   type text (JSON) and submit it
//        {op: "read", label, names: [...]}                         note the values shown
//        {op: "press", text}                                       press a button with this text
//        {op: "problems", label}                                   note the Problems list's text
//        {op: "sleep", s} | {op: "screenshot", path}
"use strict";
const fs = require("fs");
const puppeteer = require("puppeteer-core");

function arg(name, fallback) {
  const i = process.argv.indexOf("--" + name);
  return i >= 0 ? process.argv[i + 1] : fallback;
}
const sleep = (ms) => new Promise((r) => setTimeout(r, ms));

// as in probe.cjs: Studio 1.48 asks for "foxglove.websocket.v1", foxglove-sdk 0.30 accepts "foxglove.sdk.v1"
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

// the value the Parameters panel shows for `name` (parsed as JSON when it is), undefined when no such row
async function readParam(page, name) {
  return page.evaluate((name) => {
    for (const row of document.querySelectorAll("tr")) {
      const cells = row.querySelectorAll("td, th");
      if (cells.length < 2 || cells[0].innerText.trim() !== name) continue;
      const area = cells[1].querySelector("textarea");
      const text = area ? area.value : cells[1].innerText;
      try { return { found: true, value: JSON.parse(text) }; } catch (e) { return { found: true, value: text }; }
    }
    return { found: false };
  }, name);
}

function meets(value, until) {
  if ("eq" in until) return JSON.stringify(value) === JSON.stringify(until.eq);
  if ("ne" in until) return JSON.stringify(value) !== JSON.stringify(until.ne);
  if ("gt" in until) return typeof value === "number" && value > until.gt;
  if ("has" in until) return JSON.stringify(value).includes(until.has);
  return false;
}

async function setParam(page, name, text) {
  // A running run pushes parameter updates every tick and the panel re-renders its rows: a row re-drawn
  // between typing and submitting loses what was typed (seen on a loaded machine). Type and submit again, as a
  // person would, a bounded number of times.
  for (let attempt = 1; ; attempt++) {
    if (await typeAndSubmit(page, name, text)) break;
    if (attempt >= 5) throw new Error("no 'Submit change' button for parameter " + name + " after typing " + text + " (5 tries)");
    await sleep(200);
  }
  await sleep(700);  // the panel debounces a submitted value by 500 ms
}

async function typeAndSubmit(page, name, text) {
  const box = await page.evaluateHandle((name) => {
    for (const row of document.querySelectorAll("tr")) {
      const cells = row.querySelectorAll("td, th");
      if (cells.length >= 2 && cells[0].innerText.trim() === name) return cells[1].querySelector("textarea");
    }
    return null;
  }, name);
  const area = box.asElement();
  if (!area) throw new Error("no editor for parameter " + name);
  await area.click({ clickCount: 3 });
  await page.keyboard.down("Control"); await page.keyboard.press("A"); await page.keyboard.up("Control");
  await page.keyboard.press("Backspace");
  await page.keyboard.type(text);
  await sleep(300);
  return page.evaluate((name) => {
    for (const row of document.querySelectorAll("tr")) {
      const cells = row.querySelectorAll("td, th");
      if (cells.length < 2 || cells[0].innerText.trim() !== name) continue;
      const submit = [...row.querySelectorAll("button")].find((b) => b.getAttribute("aria-label") === "Submit change");
      if (submit) { submit.click(); return true; }
    }
    return false;
  }, name);
}

async function problems(page) {
  return page.evaluate(async () => {
    const tab = [...document.querySelectorAll("button, [role=tab]")].find((e) => /^Problems/.test(e.innerText.trim()));
    if (!tab) return "";
    tab.click();
    await new Promise((r) => setTimeout(r, 1500));
    // as probe.cjs reads it: the entries under the tab, in the sidebar's column (not the panels' text)
    const top = tab.getBoundingClientRect().bottom;
    const right = tab.parentElement.getBoundingClientRect().right + 40;
    const items = [...document.querySelectorAll("div, li, p, span")].filter((e) => {
      const r = e.getBoundingClientRect();
      return e.children.length === 0 && r.top >= top && r.right <= right && r.width > 0 && e.innerText.trim();
    }).map((e) => e.innerText.trim());
    return [...new Set(items)].join("\n");
  });
}

async function main() {
  const bridge = await startBridge(arg("ws-bridge"));
  const url = arg("url").replace("__BRIDGE__", encodeURIComponent("ws://127.0.0.1:" + bridge.address().port));
  const steps = JSON.parse(fs.readFileSync(arg("steps"), "utf8"));
  const browser = await puppeteer.launch({
    executablePath: arg("chromium"),
    headless: true,
    args: ["--headless", "--no-sandbox", "--disable-gpu", "--disable-background-networking",
      "--disable-component-update", "--disable-sync", "--no-first-run", "--use-angle=swiftshader",
      "--enable-unsafe-swiftshader", "--user-data-dir=" + arg("profile"), "--window-size=1600,1000"],
    defaultViewport: { width: 1600, height: 1000 },
    protocolTimeout: 180000,
  });
  const result = { errors: [], seen: [], done: 0 };
  try {
    const page = await browser.newPage();
    page.on("pageerror", (e) => result.errors.push(String(e)));
    await page.goto(url, { waitUntil: "load", timeout: 180000 });
    for (const step of steps) {
      const t0 = Date.now();
      if (step.op === "wait") {
        let last;
        for (;;) {
          last = await readParam(page, step.name);
          if (last.found && meets(last.value, step.until)) break;
          // or_gone: the run may end and close its server before Studio shows the last value (seen once beside a
          // CPU hog: "finished" was sent as the server closed); the parameter gone then ends the wait too, and
          // the test checks the end itself (exit code, the log's result)
          if (step.or_gone && !last.found) { last = { found: false, value: "(gone: the server closed)" }; break; }
          if (Date.now() - t0 > (step.timeout ?? 60) * 1000) {
            throw new Error(`${step.name} never showed ${JSON.stringify(step.until)}; last ${JSON.stringify(last)}`);
          }
          await sleep(250);
        }
        result.seen.push({ op: "wait", name: step.name, value: last.value, after_s: (Date.now() - t0) / 1000 });
      } else if (step.op === "set") {
        await setParam(page, step.name, step.text);
        result.seen.push({ op: "set", name: step.name, text: step.text });
      } else if (step.op === "read") {
        const values = {};
        for (const name of step.names) values[name] = (await readParam(page, name)).value;
        result.seen.push({ op: "read", label: step.label, values });
      } else if (step.op === "press") {
        const pressed = await page.evaluate((text) => {
          const b = [...document.querySelectorAll("button")].find((b) => b.innerText.trim() === text && !b.disabled);
          if (b) b.click();
          return Boolean(b);
        }, step.text);
        if (!pressed) throw new Error("no enabled button " + step.text);
        result.seen.push({ op: "press", text: step.text });
      } else if (step.op === "problems") {
        result.seen.push({ op: "problems", label: step.label, text: await problems(page) });
      } else if (step.op === "sleep") {
        await sleep(step.s * 1000);
      } else if (step.op === "screenshot") {
        await page.screenshot({ path: step.path });
      } else if (step.op === "dump") {
        result.seen.push({ op: "dump", text: await page.evaluate(() => document.body.innerText) });
      }
      result.done += 1;
    }
  } catch (e) {
    result.failure = String(e && e.stack ? e.stack : e);
  } finally {
    await browser.close();
    bridge.close();
    fs.writeFileSync(arg("out"), JSON.stringify(result, null, 1));
  }
}
main().catch((e) => { console.error(e); process.exit(1); });
