// The frames a view has received, and the world at any moment between them.
//
// Frames come 30 times a second (the match's frame_hz) over a network that delivers
// them unevenly; drawing the newest one as it comes would stutter. So the view plays
// a little behind the newest frame (DELAY_S, about three frames) on its own clock, and
// draws the world interpolated between the two frames around that moment: smooth at
// the display's rate, whatever it is. The clock runs at the playback speed, and is
// nudged toward its target rather than set, so small delivery jitter never shows; a
// jump (joining, a seek, a fast match the spectator only samples) resets it.

export const DELAY_S = 0.1;
const RESET_S = 0.5;
const NUDGE = 0.1;
const KEEP_S = 2;

export class Timeline {
  constructor() {
    this.clear();
  }

  clear() {
    this.frames = [];
    this.clock = null;
    this.applied = -1;
  }

  push(frame) {
    const last = this.frames[this.frames.length - 1];
    // A frame from the past (a replay seeking backwards) starts a new timeline.
    if (last && frame.tick <= last.tick) this.clear();
    this.frames.push(frame);
  }

  get newest() {
    return this.frames[this.frames.length - 1] ?? null;
  }

  /**
   * Advances the clock by `dt` wall-clock seconds at `rate`, toward `delay` behind the
   * newest frame, and returns the frames it passed (whose events are now due), oldest
   * first.
   */
  advance(dt, rate, delay = DELAY_S) {
    const newest = this.newest;
    if (!newest) return [];
    const target = newest.time_s - delay;
    // Paused (rate 0), the view shows exactly the frame it stopped on.
    if (this.clock === null || rate === 0 || Math.abs(this.clock - target) > RESET_S * Math.max(1, rate)) {
      this.clock = target;
    } else {
      this.clock += dt * rate;
      this.clock += (target - this.clock) * NUDGE;
      this.clock = Math.min(this.clock, newest.time_s);
    }
    const due = this.frames.filter((f) => f.tick > this.applied && f.time_s <= this.clock + 1e-9);
    if (due.length) this.applied = due[due.length - 1].tick;
    // Frames well behind the clock are no longer needed to interpolate.
    while (this.frames.length > 2 && this.frames[1].time_s < this.clock - KEEP_S) this.frames.shift();
    return due;
  }

  /**
   * The world at the clock: positions and headings interpolated between the frames
   * around it; everything discrete (state, score, behaviour) from the earlier frame.
   */
  sample() {
    const frames = this.frames;
    if (!frames.length) return null;
    const t = this.clock ?? frames[frames.length - 1].time_s;
    let i = frames.length - 1;
    while (i > 0 && frames[i].time_s > t) i--;
    const a = frames[i];
    const b = frames[i + 1];
    if (!b || t <= a.time_s) return { ...a, time_s: Math.max(t, a.time_s) };
    const f = (t - a.time_s) / (b.time_s - a.time_s);
    const byId = new Map(b.agents.map((agent) => [agent.id, agent]));
    return {
      ...a,
      time_s: t,
      // A ball that changes state (caught, dead, passed) jumps; it never glides home.
      ball: a.ball.state === b.ball.state
        ? { ...a.ball, position: lerpArray(a.ball.position, b.ball.position, f) }
        : a.ball,
      agents: a.agents.map((agent) => {
        const next = byId.get(agent.id);
        if (!next) return agent;
        return {
          ...agent,
          position: lerpArray(agent.position, next.position, f),
          heading: lerpAngle(agent.heading, next.heading, f),
        };
      }),
    };
  }
}

function lerpArray(a, b, f) {
  return a.map((v, i) => v + (b[i] - v) * f);
}

/** Interpolates the short way round. */
function lerpAngle(a, b, f) {
  const d = Math.atan2(Math.sin(b - a), Math.cos(b - a));
  return a + d * f;
}
