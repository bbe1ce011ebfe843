// Boots Foxglove Studio from the studio-base bundle's exports (a UMD library that put them on window).
(async function main() {
  const S = window;
  const h = React.createElement;

  class MemoryConfiguration {
    constructor() { this.values = { "launchDefault": "web", "telemetry.telemetryEnabled": false, "telemetry.crashReportingEnabled": false }; this.listeners = {}; }
    get(key) { return this.values[key]; }
    async set(key, value) { this.values[key] = value; (this.listeners[key] || []).forEach((cb) => cb(value)); }
    addChangeListener(key, cb) { (this.listeners[key] = this.listeners[key] || []).push(cb); }
    removeChangeListener(key, cb) { this.listeners[key] = (this.listeners[key] || []).filter((x) => x !== cb); }
  }

  class MemoryLayoutStorage {
    constructor(initial) { this.items = {}; for (const l of initial) { this.items[l.id] = l; } }
    async list(ns) { return Object.values(this.items); }
    async get(ns, id) { return this.items[id]; }
    async put(ns, layout) { this.items[layout.id] = layout; return layout; }
    async delete(ns, id) { delete this.items[id]; }
    async importLayouts() {}
    async migrateUnnamespacedLayouts() {}
  }

  const initial = [];
  try {
    const response = await fetch("/layout.json");
    if (response.ok) {
      const data = await response.json();
      initial.push({ id: "bt-grasp", name: "bt_grasp", permission: "CREATOR_WRITE",
        baseline: { data, savedAt: new Date().toISOString() }, working: undefined, syncInfo: undefined });
      // the layout the app opens first
      localStorage.setItem("studio.layout-manager.selected-layout-id", "bt-grasp");
    }
  } catch (e) { console.log("no layout: " + e); }

  if (S.initI18n) { await S.initI18n(); }
  const dataSources = [new S.FoxgloveWebSocketDataSourceFactory(), new S.RemoteDataSourceFactory(),
                       new S.McapLocalDataSourceFactory()];
  const app = h(S.App, {
    deepLinks: [window.location.href],
    dataSources,
    appConfiguration: new MemoryConfiguration(),
    layoutStorage: new MemoryLayoutStorage(initial),
    extensionLoaders: [],
    enableGlobalCss: true,
  });
  ReactDOM.render(app, document.getElementById("root"));
  window.__btGraspBooted = true;
})().catch((e) => { console.error("boot failed: " + (e && e.stack ? e.stack : e)); window.__btGraspBootError = String(e); });
