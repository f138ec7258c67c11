// A minimal fieldhouse bot in JavaScript: it plays one agent of a match over the
// WebSocket protocol (PROTOCOL.md). No dependencies: Node 22+ has a global WebSocket;
// Node 20 needs a flag. Get a token by creating a match with `"bot": true` on an agent:
//
//   node examples/bot.mjs ws://127.0.0.1:7878/ws/matches/ID/play TOKEN
//   node --experimental-websocket examples/bot.mjs ws://127.0.0.1:7878/ws/matches/ID/play TOKEN

const [url, token] = process.argv.slice(2);
if (!url || !token) {
  console.error("usage: node examples/bot.mjs ws://HOST:PORT/ws/matches/ID/play TOKEN");
  process.exit(2);
}
// The token goes in the query (this WebSocket API cannot set headers). A wrong token or
// match id is refused (403, 404) before the socket opens: that shows as an error event.
const ws = new WebSocket(`${url}?token=${encodeURIComponent(token)}`);
ws.onerror = (event) => {
  console.error(`WebSocket error: ${event.message ?? "connection failed"}`);
  process.exitCode = 1;
};

// Every message is one JSON object in a text frame, tagged by its "type".
ws.onmessage = (event) => {
  const msg = JSON.parse(event.data);
  switch (msg.type) {
    case "hello": // always first: the match (sport, tick_hz, perception_every_ticks, ...)
      console.log(`playing ${msg.agent} in ${msg.match.sport}`);
      break;
    case "perception": // every perception_every_ticks ticks: answer for that tick
      ws.send(JSON.stringify({ type: "command", tick: msg.tick, action: act(msg.perception) }));
      break;
    case "error": // about something we sent; the connection stays open
      console.error(`error ${msg.code}: ${msg.message}`);
      break;
    case "end": // the last message; the server then closes the socket (1000; 1001 on shutdown)
      console.log(`end (${msg.reason}): ${JSON.stringify(msg.result)}`);
      break;
    default: // ignore types this bot does not know
  }
};
ws.onclose = (event) => {
  // 1001: after `end` on shutdown; 1008: flooding; 1009: a message over the size limit.
  if (event.code !== 1000) console.error(`closed: ${event.code} ${event.reason}`);
};

// Picks an action. Points are [x, z] in metres on the ground; angles are radians from
// +x toward +z.
function act(p) {
  if ("optics" in p) {
    // A fielder (baseball, cricket). Between balls nothing moves, and each launch puts
    // the fielder back home at rest: ask for home so it stays there until it sees the
    // new ball (an order holds until the next one).
    if (p.optics === null) return { kind: "run_to", target: p.self.home };
    // In play: run to the ground point under the ball, along the bearing alpha at
    // distance_m (the rates and tan_psi are there for smarter strategies).
    const [x, z] = p.self.position;
    const { alpha, distance_m: d } = p.optics;
    return { kind: "run_to", target: [x + d * Math.cos(alpha), z + d * Math.sin(alpha)] };
  }
  // A basketball player: `self` is our id among `agents`.
  const [bx, bz] = p.basket;
  const [x, z] = p.agents.find((a) => a.id === p.self)?.position ?? p.basket;
  if (p.has_ball) {
    // With the ball: drive to the basket and shoot from within 5 m.
    if (Math.hypot(x - bx, z - bz) <= 5) return { kind: "shoot" };
    return { kind: "move_to", target: p.basket };
  }
  // Without it: wait for a pass 4 m out from the basket, on our side of the court.
  return { kind: "move_to", target: [bx + 4, z >= 0 ? 2.5 : -2.5] };
}
