// The replay player: play and pause, speed 0.25× to 8×, a seek bar, a step of one tick
// either way, a download link; and keyboard shortcuts. It sends the protocol's
// `control` messages; the server paces the frames (PROTOCOL.md, "Watching replays").
import { $ } from "./draw.js";

const SPEEDS = [0.25, 0.5, 1, 2, 4, 8];

export const KEYS = "space play/pause · ← → step · − + speed · Home start · End last frame";

export class Player {
  /**
   * `replay`: hello's `replay` object; `send(control)` sends a control; `onSeek()` is
   * called before a seek so the view forgets what it drew; `leadInS`: the seconds of
   * frames before the target a seek asks for too, so the view can rebuild what led there
   * (the flight so far, the latest decision) instead of showing a bare moment.
   */
  constructor(replay, ticksPerFrame, { send, onSeek, leadInS, tickHz }) {
    this.replay = replay;
    this.ticksPerFrame = ticksPerFrame;
    this.send = send;
    this.onSeek = onSeek;
    this.leadInS = leadInS;
    this.tickHz = tickHz;
    /** The tick the last seek went to: frames before it are its lead-in. */
    this.target = 0;
    this.playing = true;
    this.speed = 1;
    this.tick = replay.first_tick ?? 0;
    this.dragging = false;

    $("player").hidden = false;
    $("keys").textContent = KEYS;
    const seek = $("seek");
    seek.min = replay.first_tick ?? 0;
    seek.max = replay.last_tick ?? 0;
    seek.value = this.tick;
    $("speed").value = "1";
    $("download").href = `/api/replays/${encodeURIComponent(replay.id)}`;
    // No name of our own: the server's (Content-Disposition) says what the file is,
    // `ID.jsonl.zst` (format 2) or `ID.jsonl` (format 1).
    $("download").setAttribute("download", "");

    this.handlers = [
      // A clicked button gives the focus back, so the keys work right after a click.
      [$("play"), "click", (e) => { e.currentTarget.blur(); this.toggle(); }],
      [$("step"), "click", (e) => { e.currentTarget.blur(); this.step(1); }],
      [$("step-back"), "click", (e) => { e.currentTarget.blur(); this.step(-1); }],
      [$("speed"), "change", () => this.setSpeed(Number($("speed").value))],
      [seek, "input", () => { this.dragging = true; }],
      [seek, "change", () => { this.dragging = false; this.seek(Number(seek.value)); }],
      [document, "keydown", (e) => this.key(e)],
    ];
    for (const [target, event, handler] of this.handlers) target.addEventListener(event, handler);
    this.show();
  }

  close() {
    for (const [target, event, handler] of this.handlers) target.removeEventListener(event, handler);
    $("player").hidden = true;
    $("keys").textContent = "";
  }

  /** A frame arrived (the position moves with it). */
  frame(tick) {
    this.tick = tick;
    if (!this.dragging) $("seek").value = tick;
  }

  /** The recording's end: the server pauses there. */
  ended() {
    this.playing = false;
    this.show();
  }

  toggle() {
    // After the end, play starts again from the beginning, as a video player does.
    if (!this.playing && this.tick >= (this.replay.last_tick ?? 0)) this.seek(this.replay.first_tick ?? 0);
    this.playing = !this.playing;
    this.send({ type: "control", action: this.playing ? "play" : "pause" });
    this.show();
  }

  step(direction) {
    if (this.playing) this.toggle();
    const first = this.replay.first_tick ?? 0, last = this.replay.last_tick ?? 0;
    // Forward: the next frame after this tick. Back: the frame before this one.
    const target = direction > 0 ? this.tick + 1 : this.tick - this.ticksPerFrame;
    this.seek(Math.min(last, Math.max(first, target)));
  }

  seek(tick) {
    this.onSeek();
    this.tick = this.target = tick;
    this.send({ type: "control", action: "seek", tick, lead_in_s: this.leadInS });
  }

  /**
   * Whether a frame is from before the last seek's lead-in: one the server sent before
   * it read the seek, still arriving. Its events belong to another part of the match.
   */
  stale(tick) {
    return tick < this.target - Math.round(this.leadInS * this.tickHz);
  }

  setSpeed(speed) {
    this.speed = speed;
    $("speed").value = String(speed);
    this.send({ type: "control", action: "speed", speed });
    this.show();
  }

  key(e) {
    // Form controls keep their own keys (a focused button clicks on space itself).
    const control = e.target instanceof HTMLSelectElement || e.target instanceof HTMLInputElement ||
      e.target instanceof HTMLButtonElement;
    if (control || e.ctrlKey || e.metaKey || e.altKey) return;
    const i = SPEEDS.indexOf(this.speed);
    const act = {
      " ": () => this.toggle(),
      ArrowRight: () => this.step(1),
      ArrowLeft: () => this.step(-1),
      "+": () => this.setSpeed(SPEEDS[Math.min(SPEEDS.length - 1, i + 1)]),
      "=": () => this.setSpeed(SPEEDS[Math.min(SPEEDS.length - 1, i + 1)]),
      "-": () => this.setSpeed(SPEEDS[Math.max(0, i - 1)]),
      Home: () => this.seek(this.replay.first_tick ?? 0),
      End: () => this.seek(this.replay.last_tick ?? 0),
    }[e.key];
    if (!act) return;
    e.preventDefault();
    act();
  }

  show() {
    $("play").textContent = this.playing ? "Pause" : "Play";
  }

  /** What the HUD says about playback. */
  status() {
    return `${this.playing ? "playing" : "paused"} at ${this.speed}×`;
  }
}
