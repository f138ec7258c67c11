// The spectator page: a lobby of matches and a live view of one, from the WebSocket
// protocol (hello, then frames). See PROTOCOL.md.
const $ = (id) => document.getElementById(id);
let socket = null;
let lobbyTimer = null;

async function lobby() {
  $("lobby").style.display = "";
  $("view").style.display = "none";
  const load = async () => {
    try {
      const { matches } = await (await fetch("/api/matches")).json();
      const { replays } = await (await fetch("/api/replays")).json();
      $("matches").innerHTML = matches.map((m) =>
        `<tr><td><a href="#/matches/${m.id}">${m.name || m.id}</a></td><td>${m.sport}</td>` +
        `<td>${m.status}</td><td>${m.tick}</td><td>${m.spectators}</td></tr>`).join("") +
        replays.map((r) =>
        `<tr><td><a href="#/replays/${r.id}">${r.name || r.id}</a> (<a href="/api/replays/${r.id}">file</a>)</td>` +
        `<td>${r.sport}</td><td>replay${r.complete ? "" : ", incomplete"}</td><td></td><td></td></tr>`).join("");
      if (matches[0]) $("source").textContent = "motion: " + matches[0].motion_source;
    } catch (e) { $("matches").innerHTML = `<tr><td colspan="5">server unreachable</td></tr>`; }
  };
  await load();
  lobbyTimer = setInterval(load, 2000);
}

function watch(id, kind) {
  $("lobby").style.display = "none";
  $("view").style.display = "";
  let hello = null, frame = null, backoff = 500;
  const connect = () => {
    const url = `${location.protocol === "https:" ? "wss" : "ws"}://${location.host}/ws/${kind}/${id}`;
    socket = new WebSocket(url);
    socket.onopen = () => { backoff = 500; };
    socket.onmessage = (m) => {
      const msg = JSON.parse(m.data);
      if (msg.type === "hello") { hello = msg; $("title").textContent = `${msg.match.name || id} (${msg.match.sport})`; }
      if (msg.type === "frame") { frame = msg; for (const e of msg.events) log(e); }
      if (msg.type === "end") log({ kind: "end", reason: msg.reason });
      hud(hello, frame, socket.readyState);
    };
    socket.onclose = () => {
      hud(hello, frame, WebSocket.CLOSED);
      if (location.hash === `#/${kind}/${id}`) setTimeout(connect, backoff = Math.min(backoff * 2, 8000));
    };
  };
  connect();
  const draw = () => { if (hello && frame) render(hello, frame); if (location.hash === `#/${kind}/${id}`) requestAnimationFrame(draw); };
  requestAnimationFrame(draw);
}

function log(e) {
  const line = document.createElement("div");
  line.textContent = e.kind === "decision" ? `${e.agent}: ${e.reason}` : JSON.stringify(e);
  $("log").prepend(line);
  while ($("log").childElementCount > 200) $("log").lastChild.remove();
}

function hud(hello, frame, state) {
  const open = state === WebSocket.OPEN;
  const score = frame ? JSON.stringify(frame.score) : "";
  $("hud").innerHTML = `<span class="${open ? "state-open" : "state-closed"}">${open ? "live" : "reconnecting"}</span>` +
    (frame ? ` · tick ${frame.tick} · ${frame.time_s.toFixed(1)} s · ${score}` : "");
}

function render(hello, frame) {
  const c = $("field"), g = c.getContext("2d");
  const field = hello.match.field;
  const basketball = field.kind === "basketball";
  // World metres to canvas pixels: x to the right, z down (a view from above).
  const [x0, x1, z0, z1] = basketball ? [-0.5, 14.5, -8, 8] : field.kind === "cricket" ? [-70, 70, -70, 70] : [-10, 120, -10, 120];
  const s = Math.min(c.width / (x1 - x0), c.height / (z1 - z0));
  const px = (x, z) => [(x - x0) * s, (z - z0) * s];
  g.fillStyle = basketball ? "#c8a46e" : "#6a9c5a";
  g.fillRect(0, 0, c.width, c.height);
  g.strokeStyle = "#fff"; g.lineWidth = 2;
  if (basketball) {
    const [a, b] = px(0, -7.5), [d, e] = px(14, 7.5);
    g.strokeRect(a, b, d - a, e - b);
    const [bx, bz] = px(field.court.basket[0], field.court.basket[1]);
    g.beginPath(); g.arc(bx, bz, field.court.three_point_m * s, -Math.PI / 2, Math.PI / 2); g.stroke();
    g.fillStyle = "#e06c00"; g.beginPath(); g.arc(bx, bz, 0.25 * s, 0, 7); g.fill();
  } else {
    const r = (field.boundary_m || field.fence_m) * s;
    const [hx, hz] = px(0, 0);
    g.beginPath();
    if (field.kind === "cricket") g.arc(hx, hz, r, 0, 7); else g.arc(hx, hz, r, 0, Math.PI / 2);
    g.stroke();
  }
  for (const a of frame.agents) {
    const [x, z] = px(a.position[0], a.position[1]);
    g.fillStyle = a.team === "defense" ? "#b42318" : a.team === "offense" ? "#1849a9" : "#fff";
    g.beginPath(); g.arc(x, z, 6, 0, 7); g.fill();
    g.strokeStyle = "#000"; g.beginPath(); g.moveTo(x, z);
    g.lineTo(x + 14 * Math.cos(a.heading), z + 14 * Math.sin(a.heading)); g.stroke();
    g.fillStyle = "#000"; g.fillText(`${a.id} ${a.strategy || a.behaviour || ""}`, x + 8, z - 8);
  }
  const b = frame.ball.position;
  const [bx, bz] = px(b[0], b[2]);
  g.fillStyle = "rgba(0,0,0,.3)"; g.beginPath(); g.arc(bx, bz, 4, 0, 7); g.fill();
  g.fillStyle = "#ff0"; g.beginPath(); g.arc(bx, bz - b[1] * s * 0.3, 5, 0, 7); g.fill();
}

function route() {
  if (socket) { socket.onclose = null; socket.close(); socket = null; }
  clearInterval(lobbyTimer);
  const m = location.hash.match(/^#\/(matches|replays)\/([\w-]+)/);
  if (m) watch(m[2], m[1]); else lobby();
}
window.addEventListener("hashchange", route);
route();
