// A viewer that subscribes to every channel of a Foxglove WebSocket server and then stops reading (a stalled
// client). Prints SUBSCRIBED once its subscriptions are sent. Usage: node stalled_viewer.cjs ws://host:port
"use strict";
const WebSocket = require("ws");
const ws = new WebSocket(process.argv[2], ["foxglove.sdk.v1"]);
let next = 1;
ws.on("message", (data, isBinary) => {
  if (isBinary) return;
  const msg = JSON.parse(String(data));
  if (msg.op === "advertise") {
    const subscriptions = msg.channels.map((c) => ({ id: next++, channelId: c.id }));
    ws.send(JSON.stringify({ op: "subscribe", subscriptions }), () => {
      console.log("SUBSCRIBED " + subscriptions.length);
      setTimeout(() => ws._socket.pause(), 200);  // from now on nothing is read
    });
  }
});
ws.on("error", (e) => { console.error(String(e)); process.exit(1); });
setTimeout(() => process.exit(0), 120000);
