// The 3-D view (three.js, vendored in web/vendor): the match as bodies. Basketball
// players are skeletons posed from the motion-capture frame each plays, blended across
// cuts as the server blends (pose.js); fielders run the run capture's stride loops at
// their speed, phase-matched by distance; the ball flies with its shadow. Cameras:
// orbit (drag, wheel; until wheeled it pulls back to keep every runner and the ball in the
// picture), follow (behind the selected agent) and, for fly balls, the
// selected fielder's eye, looking at the ball, with the optics it uses drawn in the
// view (the image path on the plane facing home, tan ψ and its rate) from eye.js.
//
// `window.fieldhouse3d` exposes what is drawn (each body's joints, the tick shown), so
// the browser test can check the skeletons against the served poses.
import * as THREE from "./three-0.170.0.module.min.js";
import { fitLine } from "./draw.js";
import { Labels } from "./labels.js";
import { opticalSamples } from "./eye.js";
import { bones, library, posePlayer, poseRunner } from "./pose.js";

const TEAM_COLOURS = { offense: 0x2f6fe4, defense: 0xd0342c, fielding: 0xf2f2f2 };
const SELECTED_COLOUR = 0xffd400;
const HOOP_HEIGHT_M = 3.05;
/** A fly ball is 7.4 cm across; it is drawn larger so it can be seen 100 m away. */
const FLY_BALL_DRAWN_M = 0.25;
const BASKETBALL_M = 0.12;
/** How far in front of the fielder's eye the image plane is drawn, m. */
const IMAGE_PLANE_M = 4;
/** The farthest the orbit camera goes from its target, by wheel or to keep the play in view. */
const MAX_RADIUS_M = 400;
const SVG = "http://www.w3.org/2000/svg";

export class View3d {
  /** A view of the match `hello` describes, drawn into `container`. */
  constructor(container, hello) {
    this.container = container;
    this.hello = hello;
    this.basketball = hello.match.field.kind === "basketball";
    this.eyeHeight = hello.match.field.eye_height_m ?? 1.7;
    this.mode = "orbit";
    this.renders = 0;
    this.figures = new Map();
    this.run = new Map(); // fielder id → {distance, t}
    this.libs = {};
    this.failed = null;
    for (const behaviour of this.basketball ? ["dribble", "run", "defense"] : ["run"]) {
      library(behaviour).then((lib) => { this.libs[behaviour] = lib; }, (e) => { this.failed = e.message; });
    }

    this.renderer = new THREE.WebGLRenderer({ antialias: false });
    this.renderer.setPixelRatio(Math.min(2, window.devicePixelRatio || 1));
    this.canvas = this.renderer.domElement;
    this.canvas.setAttribute("aria-label", "the match in 3-D");
    this.overlay = document.createElement("div");
    this.overlay.className = "overlay3d";
    this.toolbar = document.createElement("div");
    this.toolbar.className = "cameras3d";
    const modes = [["orbit", "orbit"], ["follow", "follow"]];
    if (!this.basketball) modes.push(["eye", "fielder's eye"]);
    for (const [mode, label] of modes) {
      const b = document.createElement("button");
      b.textContent = label;
      b.dataset.camera = mode;
      b.addEventListener("click", () => this.setCamera(mode));
      this.toolbar.append(b);
    }
    // Names over the picture, laid out as the 2-D view lays them out (labels.js: never
    // over each other, a player or the ball) on a canvas that is never shown, and set as
    // text: a 2-D canvas laid over the WebGL one hid it from software compositing.
    this.nameLayer = document.createElement("div");
    this.nameLayer.className = "names3d";
    this.leaders = document.createElementNS(SVG, "svg");
    this.nameLayer.append(this.leaders);
    this.names = [];
    this.layout = document.createElement("canvas").getContext("2d");
    container.replaceChildren(this.canvas, this.nameLayer, this.overlay, this.toolbar);

    this.scene = new THREE.Scene();
    this.scene.background = new THREE.Color(this.basketball ? 0x20262b : 0x9cc7e8);
    this.scene.add(new THREE.HemisphereLight(0xffffff, 0x445544, 2.2));
    const sun = new THREE.DirectionalLight(0xffffff, 1.5);
    sun.position.set(-20, 40, 10);
    this.scene.add(sun);
    this.camera = new THREE.PerspectiveCamera(50, 4 / 3, 0.05, 2000);
    this.orbit = this.framing(hello);
    this.boneMaterial = {};
    this.bone = new THREE.CylinderGeometry(1, 1, 1, 6);
    this.head = new THREE.SphereGeometry(1, 12, 8);
    if (this.basketball) this.buildCourt(hello.match.field.court);
    else this.buildField(hello.match.field);
    this.ball = new THREE.Mesh(new THREE.SphereGeometry(this.basketball ? BASKETBALL_M : FLY_BALL_DRAWN_M, 16, 12),
      new THREE.MeshLambertMaterial({ color: this.basketball ? 0xe06a1b : 0xffffff }));
    this.shadow = new THREE.Mesh(new THREE.CircleGeometry(this.basketball ? BASKETBALL_M : FLY_BALL_DRAWN_M, 20),
      new THREE.MeshBasicMaterial({ color: 0x000000, transparent: true, opacity: 0.35 }));
    this.shadow.rotation.x = -Math.PI / 2;
    this.scene.add(this.ball, this.shadow);
    this.trail = line([], 0xffffff);
    this.imagePath = line([], 0x1849a9);
    this.imageFrame = line([], 0xffffff);
    this.scene.add(this.trail, this.imagePath, this.imageFrame);

    this.listen();
    this.state = { sport: hello.match.sport, tick: null, camera: this.mode, agents: [], renders: 0 };
    // Who the camera leaves out of the last picture: each agent (at its chest) and the
    // ball, projected as the renderer does. Worked out when asked, not every frame.
    Object.defineProperty(this.state, "outOfFrame", {
      enumerable: true,
      get: () => {
        const s = this.shownSample;
        if (!s) return [];
        return [...s.agents.map((a) => [a.id, [a.position[0], 1, a.position[1]]]), ["ball", s.ball.position]]
          .filter(([, point]) => !onCanvas(this.camera, point))
          .map(([id]) => id);
      },
    });
    window.fieldhouse3d = this.state;
    this.setCamera("orbit");
  }

  /**
   * The default orbit: a broadcast's view of where the play happens, as close as it can
   * be with all of it on the canvas. Basketball: the half court from above the half-court
   * line, looking at the basket. Baseball: from behind and above the outfielders, looking
   * back at home plate, so the fielders are in front and the ball comes toward them.
   * Cricket: the ring from high above its centre. The radius is the least (in steps of
   * 5 %) at which every point that must be seen (the court's corners, the fielders'
   * places, home, a fly ball's height) projects inside 90 % of the canvas.
   */
  framing(hello) {
    const field = hello.match.field;
    let target, azimuth, elevation, must;
    if (this.basketball) {
      const c = field.court, half = c.width_m / 2;
      target = new THREE.Vector3(c.length_m / 2, 0, 0);
      [azimuth, elevation] = [0, 0.6];
      must = [[0, 0, -half], [0, 0, half], [c.length_m, 0, -half], [c.length_m, 0, half], [c.basket[0], 3.05, c.basket[1]]];
    } else {
      const homes = hello.match.agents.map((a) => a.home).filter(Boolean);
      const [cx, cz] = homes.reduce(([x, z], h) => [x + h[0] / homes.length, z + h[1] / homes.length], [0, 0]);
      if (field.kind === "baseball" && Math.hypot(cx, cz) > 1) {
        target = new THREE.Vector3(0.6 * cx, 0, 0.6 * cz);
        [azimuth, elevation] = [Math.atan2(cz, cx), 0.45];
        // Fielders run from their places to where balls come down: keep 25 m around
        // each place in view, not the place alone.
        const around = (h) => [[25, 0], [-25, 0], [0, 25], [0, -25]].map(([dx, dz]) => [h[0] + dx, 1, h[1] + dz]);
        must = [[0, 0, 0], [cx, 30, cz], ...homes.flatMap(around)];
      } else {
        const r = field.boundary_m ?? field.fence_m ?? 100;
        target = new THREE.Vector3(0, 0, 0);
        [azimuth, elevation] = [Math.PI * 1.25, 1.0];
        must = [[r, 0, 0], [-r, 0, 0], [0, 0, r], [0, 0, -r], ...homes.map((h) => [h[0], 1, h[1]])];
      }
    }
    const orbit = { target, azimuth, elevation, radius: 3, followsPlay: true };
    orbit.radius = fitRadius(this.camera, orbit, must);
    return orbit;
  }

  /** Orbiting by pointer drag and wheel (or pinch: the browser's wheel with ctrl). */
  listen() {
    let drag = null;
    this.canvas.addEventListener("pointerdown", (e) => {
      drag = { x: e.clientX, y: e.clientY };
      this.canvas.setPointerCapture(e.pointerId);
    });
    this.canvas.addEventListener("pointermove", (e) => {
      if (!drag || this.mode !== "orbit") return;
      this.orbit.azimuth -= (e.clientX - drag.x) * 0.008;
      this.orbit.elevation = Math.min(1.5, Math.max(0.05, this.orbit.elevation + (e.clientY - drag.y) * 0.006));
      drag = { x: e.clientX, y: e.clientY };
    });
    this.canvas.addEventListener("pointerup", () => { drag = null; });
    this.canvas.addEventListener("wheel", (e) => {
      e.preventDefault();
      this.orbit.radius = Math.min(MAX_RADIUS_M, Math.max(3, (this.pulledBack ?? this.orbit.radius) * Math.exp(e.deltaY * 0.001)));
      // A chosen zoom is kept as chosen: the camera no longer pulls back for the play.
      this.orbit.followsPlay = false;
      this.pulledBack = null;
    }, { passive: false });
  }

  setCamera(mode) {
    this.mode = mode;
    this.state.camera = mode;
    for (const b of this.toolbar.children) b.classList.toggle("on", b.dataset.camera === mode);
  }

  buildCourt(court) {
    const L = court.length_m, W = court.width_m, [bx, bz] = court.basket;
    const floor = new THREE.Mesh(new THREE.PlaneGeometry(L + 4, W + 4), new THREE.MeshLambertMaterial({ color: 0xc9925a }));
    floor.rotation.x = -Math.PI / 2;
    floor.position.set(L / 2, 0, 0);
    this.scene.add(floor);
    const y = 0.005;
    const lines = [
      [[0, -W / 2], [L, -W / 2], [L, W / 2], [0, W / 2], [0, -W / 2]],
      // The key: 4.9 m wide, 5.8 m to the free-throw line.
      [[0, -2.45], [5.8, -2.45], [5.8, 2.45], [0, 2.45]],
    ];
    const arc = [];
    for (let k = 0; k <= 64; k++) {
      const a = -Math.PI / 2 + (Math.PI * k) / 64;
      const x = bx + court.three_point_m * Math.cos(a), z = bz + court.three_point_m * Math.sin(a);
      if (Math.abs(z) < W / 2) arc.push([x, z]);
    }
    lines.push(arc);
    for (const l of lines) this.scene.add(line(l.map(([x, z]) => [x, y, z]), 0xffffff));
    const steel = new THREE.MeshLambertMaterial({ color: 0x888888 });
    const board = new THREE.Mesh(new THREE.BoxGeometry(0.05, 1.05, 1.8), new THREE.MeshLambertMaterial({ color: 0xf4f4f4, transparent: true, opacity: 0.85 }));
    board.position.set(bx - 0.375, HOOP_HEIGHT_M + 0.4, bz);
    const pole = new THREE.Mesh(new THREE.BoxGeometry(0.15, HOOP_HEIGHT_M + 0.9, 0.15), steel);
    pole.position.set(-0.6, (HOOP_HEIGHT_M + 0.9) / 2, bz);
    const hoop = new THREE.Mesh(new THREE.TorusGeometry(0.23, 0.015, 8, 32), new THREE.MeshLambertMaterial({ color: 0xe0501b }));
    hoop.rotation.x = Math.PI / 2;
    hoop.position.set(bx, HOOP_HEIGHT_M, bz);
    this.scene.add(board, pole, hoop);
  }

  buildField(field) {
    const reach = (field.fence_m ?? field.boundary_m ?? 100) + 15;
    const grass = new THREE.Mesh(new THREE.CircleGeometry(reach, 64), new THREE.MeshLambertMaterial({ color: 0x5d9b4a }));
    grass.rotation.x = -Math.PI / 2;
    this.scene.add(grass);
    const ring = (r, from = 0, to = 2 * Math.PI) => {
      const pts = [];
      for (let k = 0; k <= 96; k++) {
        const a = from + ((to - from) * k) / 96;
        pts.push([r * Math.cos(a), 0.02, r * Math.sin(a)]);
      }
      return line(pts, 0xffffff);
    };
    if (field.kind === "baseball") {
      const [a, b] = field.foul_lines_deg.map((d) => (d * Math.PI) / 180);
      for (const d of [a, b]) this.scene.add(line([[0, 0.02, 0], [field.fence_m * Math.cos(d), 0.02, field.fence_m * Math.sin(d)]], 0xffffff));
      this.scene.add(ring(field.fence_m, a, b));
      const p = field.base_path_m;
      const diamond = [[0, 0], [p, 0], [p, p], [0, p], [0, 0]].map(([x, z]) => [x, 0.02, z]);
      this.scene.add(line(diamond, 0xf0e0c0));
    } else {
      this.scene.add(ring(field.boundary_m), ring(field.inner_ring_m));
      const pitch = new THREE.Mesh(new THREE.PlaneGeometry(field.pitch_length_m, 3), new THREE.MeshLambertMaterial({ color: 0xd8c49a }));
      pitch.rotation.x = -Math.PI / 2;
      pitch.position.set(-field.pitch_length_m / 2, 0.01, 0);
      this.scene.add(pitch);
    }
  }

  /** A body's meshes, made on first sight: a cylinder per bone and a head. */
  figure(id, lib, colour) {
    let f = this.figures.get(id);
    if (f && f.lib === lib) return f;
    if (f) this.scene.remove(f.group);
    const material = new THREE.MeshLambertMaterial({ color: colour });
    const group = new THREE.Group();
    const list = bones(lib);
    const meshes = list.map(() => {
      const m = new THREE.Mesh(this.bone, material);
      group.add(m);
      return m;
    });
    const headJoint = lib.joints.indexOf("Head");
    const head = new THREE.Mesh(this.head, material);
    head.scale.setScalar(0.11);
    group.add(head);
    this.scene.add(group);
    f = { lib, group, list, meshes, head, headJoint, material };
    this.figures.set(id, f);
    return f;
  }

  /** Draws `sample` (timeline.js) with `selected` the agent picked; `flight` the fly view's. */
  draw(sample, selected, flight) {
    const width = this.container.clientWidth;
    if (!width || !sample) return;
    const height = Math.round(width * 0.75);
    if (this.size !== `${width}x${height}`) {
      this.size = `${width}x${height}`;
      this.renderer.setSize(width, height, false);
      this.camera.aspect = width / height;
      this.camera.updateProjectionMatrix();
    }
    const shown = [];
    for (const a of sample.agents) {
      const behaviour = this.basketball ? (a.graph ?? a.behaviour) : "run";
      const lib = this.libs[behaviour];
      if (!lib) continue;
      let joints;
      if (this.basketball) joints = posePlayer(lib, a.node, a.blend, a.position, a.heading);
      else {
        const r = this.run.get(a.id) ?? { distance: 0, t: sample.time_s };
        const dt = sample.time_s - r.t;
        if (dt > 0 && dt < 1) r.distance += Number(a.speed) * dt;
        r.t = sample.time_s;
        this.run.set(a.id, r);
        joints = poseRunner(lib, Number(a.speed), r.distance, a.position, a.heading);
      }
      const team = this.basketball ? this.hello.match.agents.find((x) => x.id === a.id)?.team : "fielding";
      const f = this.figure(a.id, lib, TEAM_COLOURS[team] ?? 0xffffff);
      f.material.color.setHex(a.id === selected ? SELECTED_COLOUR : TEAM_COLOURS[team] ?? 0xffffff);
      pose(f, joints);
      shown.push({ id: a.id, behaviour, node: a.node ?? null, blend: a.blend ?? null, position: a.position, heading: a.heading, speed: a.speed, joints });
    }
    const [x, y, z] = sample.ball.position;
    const visible = this.basketball || sample.ball.state === "flight";
    this.ball.visible = this.shadow.visible = visible;
    this.ball.position.set(x, y, z);
    this.shadow.position.set(x, 0.01, z);
    this.shadow.scale.setScalar(1 / (1 + y / 10));
    const eyeText = this.basketball ? null : this.flyExtras(sample, selected, flight);
    this.aim(sample, selected);
    this.renderer.render(this.scene, this.camera);
    this.renders += 1;
    const c = this.camera.position;
    this.shownSample = sample;
    Object.assign(this.state, { tick: sample.tick, time_s: sample.time_s, agents: shown, renders: this.renders, camera: this.mode,
      holder: sample.ball.holder ?? null,
      eye: [c.x, c.y, c.z], looking: this.camera.getWorldDirection(new THREE.Vector3()).toArray(), ball: sample.ball.position });
    const text = this.failed ? `poses unavailable: ${this.failed}` : eyeText ?? "";
    if (text !== this.overlayText) this.overlay.textContent = this.overlayText = text;
    this.nameAgents(sample, width, height);
  }

  /**
   * Each agent's name by its head, the ball handler's saying so; a name the layout had
   * to move away from a crowd gets a line back to its head.
   */
  nameAgents(sample, width, height) {
    const pixel = (point) => {
      const p = onCanvas(this.camera, point);
      return p && [(p.x + 1) / 2 * width, (1 - p.y) / 2 * height];
    };
    const labels = new Labels(this.layout, width, height);
    const ball = pixel(sample.ball.position);
    if (ball) labels.avoid(ball[0], ball[1], 4);
    const heads = sample.agents.map((a) => [a, pixel([a.position[0], 1.9, a.position[1]])]).filter(([, at]) => at);
    for (const [, at] of heads) labels.avoid(at[0], at[1], 4);
    for (const [a, at] of heads) {
      const holds = sample.ball.holder === a.id;
      labels.add(holds ? `${a.id} · ball` : a.id, at[0], at[1],
        { font: `${holds ? "bold " : ""}12px system-ui, sans-serif`, halo: null, rank: holds ? 0 : 1 });
    }
    const placed = labels.draw(this.layout.canvas);
    while (this.names.length < placed.length) this.names.push(this.nameLayer.appendChild(document.createElement("span")));
    this.names.forEach((span, k) => {
      const box = placed[k];
      span.hidden = !box;
      if (!box) return;
      if (span.textContent !== box.text) span.textContent = box.text;
      span.classList.toggle("ball", box.text.endsWith("· ball"));
      span.style.left = `${box.x0}px`;
      span.style.top = `${box.y0}px`;
    });
    this.leaders.replaceChildren(...placed.filter((p) => p.leader).map(({ leader: [x1, y1, x2, y2] }) => {
      const l = document.createElementNS(SVG, "line");
      Object.entries({ x1, y1, x2, y2 }).forEach(([k, v]) => l.setAttribute(k, v.toFixed(1)));
      return l;
    }));
    this.nameLayer.placedLabels = placed;
  }

  /** The flight's trail and, from the fielder's eye, the image path and tan ψ. */
  flyExtras(sample, selected, flight) {
    const points = (flight ?? []).map((s) => s.ball);
    setLine(this.trail, points);
    const fielder = sample.agents.find((a) => a.id === selected);
    const show = this.mode === "eye" && fielder;
    this.imagePath.visible = this.imageFrame.visible = Boolean(show);
    if (!show) return null;
    const samples = opticalSamples(flight ?? [], selected, this.eyeHeight);
    // The image plane faces home from the fielder, as eye.js measures it: u along
    // (−fz, fx), v up, both over depth; drawn IMAGE_PLANE_M in front of the eye.
    const [px, pz] = fielder.position;
    let fx = -px, fz = -pz;
    const fl = Math.hypot(fx, fz) || 1;
    fx /= fl; fz /= fl;
    const at = (u, v) => [px + IMAGE_PLANE_M * (fx - u * fz), this.eyeHeight + IMAGE_PLANE_M * v, pz + IMAGE_PLANE_M * (fz + u * fx)];
    setLine(this.imagePath, samples.filter((s) => s.u !== undefined).map((s) => at(s.u, s.v)));
    setLine(this.imageFrame, [at(-0.5, 0), at(0.5, 0), at(0.5, 1), at(-0.5, 1), at(-0.5, 0)]);
    // What is drawn is named whatever the moment: the frame alone is a bare quadrilateral.
    const legend = `white frame: the image plane, ${IMAGE_PLANE_M} m ahead, facing home`;
    if (samples.length < 2) return `${selected}'s eye: waiting for the ball to rise above the eye · ${legend}`;
    const last = samples[samples.length - 1];
    const fit = fitLine(samples.map((s) => [s.t, s.tanPsi]));
    return `${selected}'s eye · tan ψ ${last.tanPsi.toFixed(3)}, rising ${fit ? fit.b.toFixed(3) : "–"}/s ` +
      `(R² ${fit ? fit.r2.toFixed(4) : "–"}) · ${legend}; blue: the ball's image path on it`;
  }

  aim(sample, selected) {
    const agent = sample.agents.find((a) => a.id === selected) ?? sample.agents[0];
    const cam = this.camera;
    if (this.mode === "eye" && agent) {
      cam.fov = 60;
      cam.position.set(agent.position[0], this.eyeHeight, agent.position[1]);
      const [x, y, z] = sample.ball.state === "flight" ? sample.ball.position : [0, this.eyeHeight, 0];
      cam.lookAt(x, y, z);
    } else if (this.mode === "follow" && agent) {
      cam.fov = 50;
      const back = this.basketball ? 5 : 12, up = this.basketball ? 2.5 : 5;
      const [x, z] = agent.position, h = agent.heading;
      cam.position.set(x - back * Math.cos(h), up, z - back * Math.sin(h));
      cam.lookAt(x, 1, z);
    } else {
      cam.fov = 50;
      cam.updateProjectionMatrix();
      placeOrbit(cam, this.orbit);
      if (this.orbit.followsPlay) {
        // Like a broadcast camera, pull back at once when a runner or the ball would
        // leave the picture (a fielder chasing a ball past the boundary), and ease back
        // in to the framing afterwards.
        const play = [...sample.agents.map((a) => [a.position[0], 1, a.position[1]]), sample.ball.position];
        const needed = fitRadius(cam, this.orbit, play);
        const eased = this.pulledBack == null ? needed : this.pulledBack + 0.03 * (needed - this.pulledBack);
        this.pulledBack = Math.max(needed, eased);
        placeOrbit(cam, { ...this.orbit, radius: this.pulledBack });
      }
    }
    cam.updateProjectionMatrix();
  }

  dispose() {
    this.renderer.dispose();
    this.container.replaceChildren();
    if (window.fieldhouse3d === this.state) delete window.fieldhouse3d;
  }
}

/** Puts a figure's bones and head where `joints` are. */
function pose(f, joints) {
  const up = new THREE.Vector3(0, 1, 0), a = new THREE.Vector3(), b = new THREE.Vector3(), d = new THREE.Vector3();
  f.list.forEach(([j, p], k) => {
    a.set(...joints[j]);
    b.set(...joints[p]);
    d.subVectors(a, b);
    const length = d.length();
    const m = f.meshes[k];
    m.position.addVectors(a, b).multiplyScalar(0.5);
    m.scale.set(0.04, Math.max(length, 1e-3), 0.04);
    if (length > 1e-6) m.quaternion.setFromUnitVectors(up, d.divideScalar(length));
  });
  if (f.headJoint >= 0) f.head.position.set(...joints[f.headJoint]).add(new THREE.Vector3(0, 0.08, 0));
}

function line(points, colour) {
  const l = new THREE.Line(new THREE.BufferGeometry(), new THREE.LineBasicMaterial({ color: colour }));
  setLine(l, points);
  return l;
}

function setLine(l, points) {
  l.geometry.setAttribute("position", new THREE.Float32BufferAttribute(points.flat(), 3));
  l.geometry.computeBoundingSphere();
}

/** Puts `cam` on its orbit: `radius` from `target`, at `azimuth` and `elevation`. */
function placeOrbit(cam, { target, azimuth, elevation, radius }) {
  cam.position.set(
    target.x + radius * Math.cos(elevation) * Math.cos(azimuth),
    target.y + radius * Math.sin(elevation),
    target.z + radius * Math.cos(elevation) * Math.sin(azimuth));
  cam.lookAt(target);
}

/**
 * The least radius, from `orbit.radius` up in steps of 5 %, at which every point in
 * `points` projects inside 90 % of the canvas; leaves `cam` placed there.
 */
function fitRadius(cam, orbit, points) {
  const o = { ...orbit };
  for (; ; o.radius *= 1.05) {
    placeOrbit(cam, o);
    cam.updateMatrixWorld();
    if (o.radius >= MAX_RADIUS_M || points.every((point) => onCanvas(cam, point, 0.9))) return Math.min(o.radius, MAX_RADIUS_M);
  }
}

/**
 * Where `point` projects through `cam` (normalised: −1..1 across and up the canvas) if
 * in front of it and within `margin` of the canvas (1: all of it); else null.
 */
function onCanvas(cam, [x, y, z], margin = 1) {
  const p = new THREE.Vector3(x, y, z).project(cam);
  return Math.abs(p.x) <= margin && Math.abs(p.y) <= margin && p.z < 1 ? p : null;
}
