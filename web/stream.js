// One WebSocket to a match or a replay, kept open: on an unexpected close it reconnects
// with exponential backoff (0.5 s doubling to 8 s), and says so through `onState`.
// A match that has ended (`end` received, other than for a server shutdown) is not
// reconnected; a replay socket stays open after its `end`, as the server keeps it.

const FIRST_BACKOFF_MS = 500;
const MAX_BACKOFF_MS = 8000;

export class Stream {
  /**
   * `path`: `/ws/matches/ID` or `/ws/replays/ID`. `onMessage(msg)` gets each parsed
   * message; `onState({state, detail})` each change: `connecting`, `live`, `ended`
   * or `retrying` (detail: when).
   * `endIsFinal`: false for replays, whose socket outlives their `end`.
   */
  constructor(path, { onMessage, onState, endIsFinal = true }) {
    this.url = `${location.protocol === "https:" ? "wss" : "ws"}://${location.host}${path}`;
    this.onMessage = onMessage;
    this.onState = onState;
    this.endIsFinal = endIsFinal;
    this.backoff = FIRST_BACKOFF_MS;
    this.attempt = 0;
    this.ended = false;
    this.closed = false;
    this.socket = null;
    this.timer = null;
    this.connect();
  }

  connect() {
    this.attempt += 1;
    this.onState({ state: "connecting", detail: this.attempt > 1 ? `attempt ${this.attempt}` : "" });
    const socket = new WebSocket(this.url);
    this.socket = socket;
    socket.onopen = () => {
      this.backoff = FIRST_BACKOFF_MS;
      this.attempt = 0;
      this.onState({ state: "live", detail: "" });
    };
    socket.onmessage = (event) => {
      let msg;
      try { msg = JSON.parse(event.data); } catch { return; }
      // A match that ends for good is not reconnected; one ended by the server
      // shutting down may be back when the server restarts, so keep trying.
      if (msg.type === "end") this.ended = this.endIsFinal && msg.reason !== "shutdown";
      this.onMessage(msg);
    };
    socket.onclose = () => {
      if (this.closed) return;
      if (this.ended) { this.onState({ state: "ended", detail: "" }); return; }
      const wait = this.backoff;
      this.backoff = Math.min(2 * this.backoff, MAX_BACKOFF_MS);
      this.onState({ state: "retrying", detail: `server gone; reconnecting in ${(wait / 1000).toFixed(1)} s` });
      this.timer = setTimeout(() => this.connect(), wait);
    };
  }

  /** Sends a message if the socket is open; says whether it went. */
  send(msg) {
    if (this.socket?.readyState !== WebSocket.OPEN) return false;
    this.socket.send(JSON.stringify(msg));
    return true;
  }

  close() {
    this.closed = true;
    clearTimeout(this.timer);
    const socket = this.socket;
    if (!socket) return;
    // Closing a socket that is still connecting makes the browser log an error; let it
    // open first and close it then.
    if (socket.readyState === WebSocket.CONNECTING) socket.onopen = () => socket.close(1000);
    else socket.close(1000);
  }
}
