// twinloop view: the robot in 3D, its recordings replayed (the second and later
// as translucent ghosts), overlays, synchronised plots and joint sliders.
//
// Data comes from the twinloop server (scene.json, robot.urdf, mesh/N.ext,
// recording/N.json|bin) or, in an exported file, from window.TWINLOOP_EMBED.
// World frame as in twinloop: z up, x forward, metres.
//
// URL parameters (also what the browser tests use):
//   t=S            start paused at time S
//   camera=px,py,pz,tx,ty,tz   camera position and target; fov=DEG vertical field of view
//   bare=1         the 3D view alone, filling the window
//   bg=RRGGBB      background colour; overlays=a,b,...  overlays on (grid, com, support, ...)
//   snapshot=1     put the rendered image (PNG data URL) in #snapshot
  //   pose=j:rad,... pose the robot by the joint sliders
  //   aa=0|1         antialiasing off/on (default: off with software WebGL)
  //   bench=S        play S seconds at 1x from the start and report frame times in #status
'use strict';
(function () {
  const { THREE, OrbitControls, STLLoader, OBJLoader, ColladaLoader, URDFLoader, uPlot } = window.TL;
  const EMBED = window.TWINLOOP_EMBED || null;
  const params = new URLSearchParams(location.search);
  const GHOST_COLOURS = [null, 0x1e88e5, 0xe53935, 0x43a047, 0x8e24aa];
  const SWATCHES = ['#9e9e9e', '#1e88e5', '#e53935', '#43a047', '#8e24aa'];
  const GRAVITY = 9.81;
  const CONTACT_HEIGHT = 0.01; // m: geometry this close to the ground counts as touching it
  const MAX_SUPPORT_POINTS = 256;

  // ---- status for people (banner) and for tests (#status JSON) ----
  const status = { ready: false, errors: [], warnings: [], recordings: [], com: null, frame: 0, antialias: null };
  window.twinloop = status;
  const statusEl = document.getElementById('status');
  function publish() { statusEl.textContent = JSON.stringify(status); }
  const consoleError = console.error.bind(console);
  console.error = function (...args) {
    status.errors.push(args.map(String).join(' '));
    publish();
    consoleError(...args);
  };
  window.addEventListener('error', (e) => { status.errors.push(String(e.message || e)); publish(); });
  window.addEventListener('unhandledrejection', (e) => {
    status.errors.push('unhandled: ' + String(e.reason && e.reason.stack || e.reason)); publish();
  });
  function warn(message) {
    status.warnings.push(message);
    console.warn('twinloop view: ' + message);
    const div = document.createElement('div');
    div.textContent = message;
    document.getElementById('warnings').appendChild(div);
    publish();
  }

  // ---- data access: the server, or the embedded copy of an exported file ----
  function base64Bytes(text) {
    const bin = atob(text);
    const out = new Uint8Array(bin.length);
    for (let i = 0; i < bin.length; i++) out[i] = bin.charCodeAt(i);
    return out.buffer;
  }
  async function fetchOk(url) {
    const r = await fetch(url);
    if (!r.ok) throw new Error(url + ': HTTP ' + r.status);
    return r;
  }
  const data = {
    scene: async () => EMBED ? EMBED.scene : (await fetchOk('scene.json')).json(),
    urdf: async () => EMBED ? EMBED.urdf : (await fetchOk('robot.urdf')).text(),
    recordingInfo: async (i) => EMBED ? EMBED.recordings[i].info : (await fetchOk('recording/' + i + '.json')).json(),
    recordingData: async (i) => EMBED ? base64Bytes(EMBED.recordings[i].data) : (await fetchOk('recording/' + i + '.bin')).arrayBuffer(),
    meshUrl: (url) => EMBED ? 'data:application/octet-stream;base64,' + EMBED.meshes[url] : url,
  };

  // ---- three.js scene, z up ----
  THREE.Object3D.DEFAULT_UP.set(0, 0, 1);
  const host = document.getElementById('view3d');
  if (params.get('bare')) document.body.classList.add('bare');
  // Antialiasing is multisampling, which software WebGL (SwiftShader, llvmpipe)
  // pays for in full: measured 29 fps with it and 43 without on the same scene,
  // against 52 for an empty canvas. Off there by default; aa=1 or aa=0 decide.
  function softwareGL() {
    try {
      const g = document.createElement('canvas').getContext('webgl2');
      const ext = g.getExtension('WEBGL_debug_renderer_info');
      const name = String(g.getParameter(ext ? ext.UNMASKED_RENDERER_WEBGL : g.RENDERER));
      const lose = g.getExtension('WEBGL_lose_context');
      if (lose) lose.loseContext();
      return /swiftshader|llvmpipe|softpipe|software/i.test(name);
    } catch (e) { return false; }
  }
  const antialias = params.has('aa') ? params.get('aa') !== '0' : !softwareGL();
  const renderer = new THREE.WebGLRenderer({ antialias, preserveDrawingBuffer: !!params.get('snapshot') });
  renderer.setPixelRatio(window.devicePixelRatio || 1);
  status.antialias = antialias;
  host.appendChild(renderer.domElement);
  const scene = new THREE.Scene();
  scene.background = new THREE.Color(params.get('bg') ? '#' + params.get('bg') : '#f4f4f2');
  const camera = new THREE.PerspectiveCamera(Number(params.get('fov') || 45), 1, 0.01, 100);
  camera.up.set(0, 0, 1);
  camera.position.set(1.2, -1.2, 0.8);
  const controls = new OrbitControls(camera, renderer.domElement);
  controls.target.set(0, 0, 0.3);
  scene.add(new THREE.HemisphereLight(0xffffff, 0x888888, 2.0));
  const sun = new THREE.DirectionalLight(0xffffff, 1.5);
  sun.position.set(2, -3, 5);
  scene.add(sun);
  const grid = new THREE.GridHelper(4, 40, 0x888888, 0xcccccc);
  grid.rotation.x = Math.PI / 2;
  scene.add(grid);

  function resize() {
    const w = host.clientWidth || window.innerWidth, h = host.clientHeight || window.innerHeight;
    renderer.setSize(w, h);
    camera.aspect = w / h;
    camera.updateProjectionMatrix();
  }
  window.addEventListener('resize', () => { resize(); plots.resize(); requestRender(); });
  // The view's box also changes when the timeline and plot appear.
  if (window.ResizeObserver) new ResizeObserver(() => { resize(); requestRender(); }).observe(host);

  // ---- robots: one per recording (the first solid, the others ghosts) ----
  const meshCache = new Map(); // url -> Promise<geometry or Object3D>
  function loadMeshAsset(url) {
    if (!meshCache.has(url)) {
      const ext = url.split('.').pop().toLowerCase();
      const src = data.meshUrl(url);
      meshCache.set(url, new Promise((resolve, reject) => {
        if (ext === 'stl') new STLLoader().load(src, resolve, undefined, reject);
        else if (ext === 'obj') new OBJLoader().load(src, resolve, undefined, reject);
        else if (ext === 'dae') new ColladaLoader().load(src, (c) => resolve(c.scene), undefined, reject);
        else reject(new Error('unknown mesh type ' + ext));
      }));
    }
    return meshCache.get(url);
  }

  // Parse the URDF into a robot; resolves once every mesh has loaded.
  function buildRobot(urdfText) {
    return new Promise((resolve) => {
      let pending = 0, parsed = null;
      const finish = () => { if (pending === 0 && parsed) resolve(parsed); };
      const loader = new URDFLoader();
      loader.loadMeshCb = (path, manager, material, done) => {
        pending++;
        loadMeshAsset(path).then((asset) => {
          let obj;
          if (asset.isBufferGeometry) obj = new THREE.Mesh(asset, material);
          else {
            obj = asset.clone(true);
            obj.traverse((c) => { if (c.isMesh && !c.userData.keepMaterial) c.material = material; });
          }
          done(obj);
        }).catch((err) => {
          warn('mesh ' + path + ' could not be read (' + (err && err.message || err) + '); that link is not drawn');
          done(null, err);
        }).finally(() => { pending--; finish(); });
      };
      parsed = loader.parse(urdfText);
      finish();
    });
  }

  // Give a robot its own materials: the solid one keeps its colours, a ghost is
  // translucent in one colour.
  function paint(robot, colour) {
    robot.traverse((c) => {
      if (!c.isMesh) return;
      const m = (Array.isArray(c.material) ? c.material[0] : c.material).clone();
      if (colour !== null) {
        m.color = new THREE.Color(colour);
        m.transparent = true;
        m.opacity = 0.35;
        m.depthWrite = false;
      }
      c.material = m;
      c.userData.baseColour = m.color.clone();
    });
  }

  // ---- geometry helpers ----
  const tmpBox = new THREE.Box3();
  const tmpV = new THREE.Vector3();
  function visualMeshes(robot) {
    const out = [];
    robot.traverse((c) => { if (c.isMesh && !c.userData.overlay) out.push(c); });
    return out;
  }
  // World corners of each visual's bounding box, into `out` (reused frame to frame).
  function visualCorners(meshes, out) {
    while (out.length < 8 * meshes.length) out.push(new THREE.Vector3());
    let k = 0;
    for (const m of meshes) {
      const g = m.geometry;
      if (!g.boundingBox) g.computeBoundingBox();
      const b = g.boundingBox;
      for (let i = 0; i < 8; i++) {
        out[k++].set(i & 1 ? b.max.x : b.min.x, i & 2 ? b.max.y : b.min.y, i & 4 ? b.max.z : b.min.z).applyMatrix4(m.matrixWorld);
      }
    }
    return out;
  }
  // The world bounding box of a robot's visual geometry (not its overlays).
  const tmpMeshBox = new THREE.Box3();
  function visualBox(robot, box) {
    box.makeEmpty();
    for (const m of visualMeshes(robot)) {
      if (!m.geometry.boundingBox) m.geometry.computeBoundingBox();
      box.union(tmpMeshBox.copy(m.geometry.boundingBox).applyMatrix4(m.matrixWorld));
    }
    return box;
  }
  // Andrew's monotone chain: the convex hull of 2-D points, counter-clockwise.
  function convexHull(points) {
    const p = points.slice().sort((a, b) => a.x - b.x || a.y - b.y);
    if (p.length < 3) return p;
    const cross = (o, a, b) => (a.x - o.x) * (b.y - o.y) - (a.y - o.y) * (b.x - o.x);
    const lower = [], upper = [];
    for (const q of p) {
      while (lower.length >= 2 && cross(lower[lower.length - 2], lower[lower.length - 1], q) <= 0) lower.pop();
      lower.push(q);
    }
    for (let i = p.length - 1; i >= 0; i--) {
      const q = p[i];
      while (upper.length >= 2 && cross(upper[upper.length - 2], upper[upper.length - 1], q) <= 0) upper.pop();
      upper.push(q);
    }
    upper.pop(); lower.pop();
    return lower.concat(upper);
  }

  // ---- overlays of one robot ----
  function makeOverlays(robot, info, colour) {
    const group = new THREE.Group();
    scene.add(group);
    const tint = colour === null ? 0xd32f2f : colour;
    const com = new THREE.Mesh(new THREE.SphereGeometry(0.015, 16, 12), new THREE.MeshBasicMaterial({ color: tint }));
    const comGround = new THREE.Mesh(new THREE.CircleGeometry(0.012, 24), new THREE.MeshBasicMaterial({ color: tint }));
    const comLineGeom = new THREE.BufferGeometry().setFromPoints([new THREE.Vector3(), new THREE.Vector3()]);
    const comLine = new THREE.Line(comLineGeom, new THREE.LineDashedMaterial({ color: tint, dashSize: 0.01, gapSize: 0.01 }));
    // One fixed buffer for the polygon (a new attribute each frame would leak GPU buffers).
    const supportGeom = new THREE.BufferGeometry();
    const supportPos = new THREE.BufferAttribute(new Float32Array(3 * MAX_SUPPORT_POINTS), 3);
    supportPos.setUsage(THREE.DynamicDrawUsage);
    supportGeom.setAttribute('position', supportPos);
    supportGeom.setDrawRange(0, 0);
    const support = new THREE.LineLoop(supportGeom, new THREE.LineBasicMaterial({ color: colour === null ? 0x2e7d32 : colour }));
    const comGroup = new THREE.Group();
    comGroup.add(com, comGround, comLine);
    // Drawn over the robot: the CoM is inside the body.
    for (const o of [com, comGround, comLine, support]) { o.material.depthTest = false; o.renderOrder = 10; }
    group.add(comGroup, support);
    // Link frames and inertia boxes ride on their links.
    const frames = [], boxes = [];
    const massive = [];
    for (const l of info.links) {
      const link = robot.links[l.name];
      if (!link) continue;
      if (l.mass > 0) massive.push({ link, mass: l.mass, com: new THREE.Vector3(...l.com) });
      const axes = new THREE.AxesHelper(0.05);
      axes.userData.overlay = true;
      axes.visible = false;
      link.add(axes);
      frames.push(axes);
      if (l.inertia_box) {
        const b = l.inertia_box;
        const box = new THREE.LineSegments(
          new THREE.EdgesGeometry(new THREE.BoxGeometry(...b.size.map((s) => Math.max(s, 1e-4)))),
          new THREE.LineBasicMaterial({ color: 0x6a1b9a }));
        box.userData.overlay = true;
        box.position.set(...b.xyz);
        box.quaternion.setFromEuler(new THREE.Euler(b.rpy[0], b.rpy[1], b.rpy[2], 'ZYX'));
        box.visible = false;
        link.add(box);
        boxes.push(box);
      }
    }
    const totalMass = massive.reduce((s, m) => s + m.mass, 0);
    const meshes = visualMeshes(robot);
    const corners = [];
    const comWorld = new THREE.Vector3();
    return {
      group, comGroup, support, frames, boxes, comWorld,
      update(show) {
        comGroup.visible = show.com;
        support.visible = show.support;
        for (const f of frames) f.visible = show.frames;
        for (const b of boxes) b.visible = show.inertia;
        comWorld.set(0, 0, 0);
        for (const m of massive) comWorld.addScaledVector(tmpV.copy(m.com).applyMatrix4(m.link.matrixWorld), m.mass);
        if (totalMass > 0) comWorld.multiplyScalar(1 / totalMass);
        com.position.copy(comWorld);
        comGround.position.set(comWorld.x, comWorld.y, 0.001);
        const pos = comLineGeom.attributes.position;
        pos.setXYZ(0, comWorld.x, comWorld.y, comWorld.z);
        pos.setXYZ(1, comWorld.x, comWorld.y, 0);
        pos.needsUpdate = true;
        comLine.computeLineDistances();
        if (show.support) {
          visualCorners(meshes, corners);
          const touching = corners.filter((c) => c.z < CONTACT_HEIGHT);
          const hull = convexHull(touching);
          const n = Math.min(hull.length, MAX_SUPPORT_POINTS);
          for (let i = 0; i < n; i++) supportPos.setXYZ(i, hull[i].x, hull[i].y, 0.002);
          supportPos.needsUpdate = true;
          supportGeom.setDrawRange(0, n);
          supportGeom.computeBoundingSphere();
        }
      },
    };
  }

  // ---- recordings ----
  // A recording: its columns as Float32Arrays, its robot, its time offset.
  function columnViews(info, buffer) {
    const cols = {};
    info.columns.forEach((name, c) => { cols[name] = new Float32Array(buffer, c * info.rows * 4, info.rows); });
    return cols;
  }
  // The last sample at or before time t (the first if t is earlier).
  function sampleAt(t, times) {
    let lo = 0, hi = times.length - 1;
    if (t <= times[0]) return 0;
    if (t >= times[hi]) return hi;
    while (hi - lo > 1) {
      const mid = (lo + hi) >> 1;
      if (times[mid] <= t) lo = mid; else hi = mid;
    }
    return lo;
  }

  // ---- state ----
  const state = {
    info: null, urdf: null,
    actors: [],          // {robot, overlays, rec|null, offset, colour, lift, visible}
    now: 0, t0: 0, t1: 0, playing: false, speed: 1, manual: false,
    show: { grid: true, com: true, support: true, cop: true, limits: true, frames: false, inertia: false },
  };
  const LIMIT_COLOUR = new THREE.Color(0xd32f2f);

  function poseActor(actor) {
    const { robot, rec } = actor;
    const joints = state.info.joints;
    if (rec && !state.manual) {
      const i = sampleAt(state.now - actor.offset, rec.cols.t);
      actor.sample = i;
      for (let j = 0; j < joints.length; j++) {
        const col = rec.jointCols[j];
        robot.joints[joints[j].name] && robot.joints[joints[j].name].setJointValue(col ? col[i] : 0);
      }
      if (rec.info.has_base) {
        const c = rec.cols;
        robot.position.set(c['q:base.x'][i], c['q:base.y'][i], c['q:base.z'][i]);
        robot.quaternion.set(c['q:base.qx'][i], c['q:base.qy'][i], c['q:base.qz'][i], c['q:base.qw'][i]).normalize();
      }
    } else if (actor === state.actors[0] && live.frame && !state.manual) {
      live.apply(robot);
    } else if (actor === state.actors[0]) {
      sliders.apply(robot);
    }
    robot.updateMatrixWorld(true);
    if (state.show.limits && actor.colour === null) colourLimits(actor);
  }

  function colourLimits(actor) {
    for (const j of state.info.joints) {
      const joint = actor.robot.joints[j.name];
      if (!joint || j.lower === null || j.upper === null) continue;
      const v = joint.angle;
      const tol = Math.max(1e-3 * (j.upper - j.lower), 1e-4);
      const atLimit = v <= j.lower + tol || v >= j.upper - tol;
      if (atLimit === !!joint.userData.atLimit) continue;
      joint.userData.atLimit = atLimit;
      const link = joint.children.find((c) => c.isURDFLink);
      if (!link) continue;
      for (const c of link.children) {
        if (!c.isURDFVisual) continue;
        c.traverse((m) => { if (m.isMesh && m.userData.baseColour) m.material.color.copy(atLimit ? LIMIT_COLOUR : m.userData.baseColour); });
      }
    }
  }

  // Centre of pressure and ground reaction arrows from foot:* or grf/cop columns.
  const copGroup = new THREE.Group();
  scene.add(copGroup);
  function copSources(rec) {
    const out = [];
    for (const name of rec.info.columns) {
      const m = /^foot:(.+)\.fz$/.exec(name);
      if (m && rec.cols['foot:' + m[1] + '.cop.x'] && rec.cols['foot:' + m[1] + '.cop.y']) {
        out.push({ fz: rec.cols[name], x: rec.cols['foot:' + m[1] + '.cop.x'], y: rec.cols['foot:' + m[1] + '.cop.y'] });
      }
    }
    if (rec.cols['grf.fz'] && rec.cols['cop.x'] && rec.cols['cop.y']) {
      out.push({ fz: rec.cols['grf.fz'], fx: rec.cols['grf.fx'], fy: rec.cols['grf.fy'], x: rec.cols['cop.x'], y: rec.cols['cop.y'] });
    }
    return out.map((s) => {
      const arrow = new THREE.ArrowHelper(new THREE.Vector3(0, 0, 1), new THREE.Vector3(), 0.1, 0x00897b, 0.02, 0.012);
      // Drawn through the foot and leg it starts inside.
      for (const part of [arrow.line, arrow.cone]) { part.material.depthTest = false; part.renderOrder = 11; }
      copGroup.add(arrow);
      return Object.assign(s, { arrow });
    });
  }
  function updateCop() {
    copGroup.visible = state.show.cop;
    const main = state.actors[0];
    if (!main || !main.rec || !state.show.cop) return;
    const i = main.sample;
    const scale = 0.4 / Math.max(state.info.total_mass * GRAVITY, 1); // body weight = 0.4 m
    for (const s of main.rec.copSources) {
      const fz = s.fz[i];
      const f = new THREE.Vector3(s.fx ? s.fx[i] : 0, s.fy ? s.fy[i] : 0, fz);
      const on = fz > 0.5 && Number.isFinite(s.x[i]) && Number.isFinite(s.y[i]);
      s.arrow.visible = on;
      if (!on) continue;
      s.arrow.position.set(s.x[i], s.y[i], 0.003);
      s.arrow.setDirection(f.clone().normalize());
      s.arrow.setLength(Math.max(f.length() * scale, 0.02), 0.02, 0.012);
    }
  }

  // ---- live: the newest state of a running source, over a websocket ----
  const live = {
    frame: null, lags: [], recvLags: [], frames: 0,
    connect() {
      const ws = new WebSocket((location.protocol === 'https:' ? 'wss://' : 'ws://') + location.host + '/live');
      ws.onmessage = (e) => {
        this.frame = JSON.parse(e.data);
        this.frames++;
        // Lag on arrival (server and network) apart from lag on screen (plus the
        // wait for the browser's next frame and the drawing).
        this.recvLags.push(Date.now() - this.frame.sent_ms);
        if (this.recvLags.length > 600) this.recvLags.shift();
        this.pending = true;
        requestRender();
      };
      ws.onclose = () => { warn('live view: the connection closed (the source stopped or the server ended)'); };
      document.getElementById('no-recordings').textContent = 'live';
    },
    apply(robot) {
      const f = this.frame;
      const joints = state.info.joints;
      for (let j = 0; j < joints.length; j++) {
        const v = f.q[j];
        if (v !== null && robot.joints[joints[j].name]) robot.joints[joints[j].name].setJointValue(v);
      }
      if (f.base && f.base.every((v) => v !== null)) {
        robot.position.set(f.base[0], f.base[1], f.base[2]);
        robot.quaternion.set(f.base[3], f.base[4], f.base[5], f.base[6]).normalize();
      }
    },
    // Called once the frame is on screen: lag from the publisher's clock.
    drawn() {
      if (!this.pending) return;
      this.pending = false;
      this.lags.push(Date.now() - this.frame.sent_ms);
      if (this.lags.length > 600) this.lags.shift();
      const sorted = this.lags.slice().sort((a, b) => a - b);
      const recv = this.recvLags.slice().sort((a, b) => a - b);
      const at = (a, p) => a[Math.min(a.length - 1, Math.floor(p * a.length))];
      status.live = {
        frames: this.frames, t: this.frame.t,
        lag_median_ms: at(sorted, 0.5), lag_p95_ms: at(sorted, 0.95), lag_max_ms: sorted[sorted.length - 1],
        recv_lag_median_ms: at(recv, 0.5), recv_lag_p95_ms: at(recv, 0.95), recv_lag_max_ms: recv[recv.length - 1],
      };
      if (this.frames % 30 === 0 || this.frames === 1) publish();
      takeSnapshot();
    },
  };

  // ---- joint sliders ----
  const sliders = {
    inputs: [],
    build(joints) {
      const list = document.getElementById('slider-list');
      for (const j of joints) {
        const lo = j.lower !== null ? j.lower : -Math.PI, hi = j.upper !== null ? j.upper : Math.PI;
        const row = document.createElement('label');
        row.className = 'slider';
        const name = document.createElement('span'); name.textContent = j.name;
        const val = document.createElement('span'); val.textContent = '0';
        const input = document.createElement('input');
        Object.assign(input, { type: 'range', min: lo, max: hi, step: 'any' });
        input.value = Math.min(Math.max(0, lo), hi);
        input.addEventListener('input', () => {
          state.manual = true; state.playing = false; updatePlayButton();
          val.textContent = Number(input.value).toFixed(3);
          requestRender();
        });
        row.append(name, val, input);
        list.appendChild(row);
        this.inputs.push({ joint: j.name, input, val });
      }
    },
    // A pose from the URL (pose=joint:rad,joint:rad): the sliders take over.
    set(text) {
      for (const item of text.split(',')) {
        const [name, value] = item.split(':');
        const s = this.inputs.find((i) => i.joint === name);
        if (!s || !Number.isFinite(Number(value))) { warn('pose: no joint "' + name + '" or not a number: ' + item); continue; }
        s.input.value = Number(value);
        s.val.textContent = Number(value).toFixed(3);
      }
      state.manual = true;
    },
    apply(robot) {
      for (const s of this.inputs) if (robot.joints[s.joint]) robot.joints[s.joint].setJointValue(Number(s.input.value));
    },
    follow(robot) {
      for (const s of this.inputs) {
        const j = robot.joints[s.joint];
        if (!j) continue;
        s.input.value = j.angle;
        s.val.textContent = Number(j.angle).toFixed(3);
      }
    },
  };

  // ---- synchronised plots (uPlot) ----
  function axisNumber(v) {
    if (v === 0) return '0';
    return Math.abs(v) < 1e-3 || Math.abs(v) >= 1e5 ? v.toExponential(1) : String(Number(v.toPrecision(3)));
  }
  const plots = {
    u: null, cursor: null, xs: null,
    build() {
      const select = document.getElementById('plot-columns');
      const filter = document.getElementById('plot-filter');
      const recs = state.actors.filter((a) => a.rec);
      if (!recs.length) return;
      document.getElementById('plot-picker').hidden = false;
      for (const [k, a] of recs.entries()) {
        for (const name of a.rec.info.columns) {
          if (name === 't') continue;
          const o = document.createElement('option');
          o.value = k + '\u0000' + name;
          o.textContent = (recs.length > 1 ? (k + 1) + ': ' : '') + name;
          select.appendChild(o);
        }
      }
      // Start with the first joint of every recording: the runs side by side.
      const first = state.info.joints.length ? 'q:' + state.info.joints[0].name : null;
      for (const o of select.options) if (first && o.value.endsWith('\u0000' + first)) o.selected = true;
      select.addEventListener('change', () => this.draw());
      filter.addEventListener('input', () => {
        const f = filter.value.toLowerCase();
        for (const o of select.options) o.hidden = f && !o.textContent.toLowerCase().includes(f);
      });
      this.draw();
    },
    draw() {
      const el = document.getElementById('plot');
      if (this.u) { this.u.destroy(); this.u = null; }
      el.innerHTML = '';
      const recs = state.actors.filter((a) => a.rec);
      const picked = [...document.getElementById('plot-columns').selectedOptions].map((o) => o.value.split('\u0000'));
      if (!picked.length) return;
      // One time axis: the first picked recording's samples, shifted by its offset;
      // other series are sampled at those instants.
      const base = recs[Number(picked[0][0])];
      const xs = Float64Array.from(base.rec.cols.t, (t) => t + base.offset);
      const series = [{}], columns = [xs];
      for (const [k, name] of picked) {
        const a = recs[Number(k)];
        const col = a.rec.cols[name];
        const ys = a === base ? col : Float64Array.from(xs, (x) => col[sampleAt(x - a.offset, a.rec.cols.t)]);
        columns.push(ys);
        series.push({ label: (recs.length > 1 ? (Number(k) + 1) + ': ' : '') + name, stroke: SWATCHES[Number(k) % SWATCHES.length] === '#9e9e9e' ? '#333' : SWATCHES[Number(k) % SWATCHES.length], width: 1 });
      }
      this.xs = xs;
      const opts = {
        width: Math.max(el.clientWidth, 300), height: 180,
        scales: { x: { time: false } },
        // Small values (rad, m) keep three significant digits on the axis.
        axes: [{}, { values: (u, vals) => vals.map(axisNumber), size: 64 }],
        series, legend: { live: false },
        cursor: { drag: { x: false, y: false } },
      };
      this.u = new uPlot(opts, columns, el);
      this.cursor = document.createElement('div');
      this.cursor.className = 'cursor-line';
      this.u.over.appendChild(this.cursor);
      this.u.over.addEventListener('click', (e) => seek(this.u.posToVal(e.offsetX, 'x')));
      this.moveCursor();
    },
    moveCursor() {
      if (!this.u) return;
      this.cursor.style.left = this.u.valToPos(state.now, 'x') + 'px';
    },
    resize() {
      if (this.u) this.u.setSize({ width: Math.max(document.getElementById('plot').clientWidth, 300), height: 180 });
    },
  };

  // ---- timeline ----
  const scrub = document.getElementById('scrub');
  const sliderPanel = document.getElementById('sliders');
  const clock = document.getElementById('clock');
  function updatePlayButton() { document.getElementById('play').innerHTML = state.playing ? '&#10074;&#10074;' : '&#9654;'; }
  function span() {
    let t0 = Infinity, t1 = -Infinity;
    for (const a of state.actors) if (a.rec) { t0 = Math.min(t0, a.rec.info.t0 + a.offset); t1 = Math.max(t1, a.rec.info.t1 + a.offset); }
    state.t0 = Number.isFinite(t0) ? t0 : 0; state.t1 = Number.isFinite(t1) ? t1 : 0;
    scrub.min = state.t0; scrub.max = state.t1;
  }
  function seek(t) {
    state.manual = false;
    state.now = Math.min(Math.max(t, state.t0), state.t1);
    requestRender();
  }
  function step(direction) {
    const main = state.actors.find((a) => a.rec);
    if (!main) return;
    state.playing = false; updatePlayButton();
    const times = main.rec.cols.t;
    const i = sampleAt(state.now - main.offset, times);
    const j = Math.min(Math.max(i + direction, 0), times.length - 1);
    seek(times[j] + main.offset);
  }
  function bindTimeline() {
    document.getElementById('timeline').hidden = false;
    document.getElementById('play').addEventListener('click', () => {
      if (state.now >= state.t1) state.now = state.t0;
      state.manual = false; state.playing = !state.playing; updatePlayButton(); requestRender();
    });
    document.getElementById('step-back').addEventListener('click', () => step(-1));
    document.getElementById('step-fwd').addEventListener('click', () => step(1));
    document.getElementById('speed').addEventListener('change', (e) => { state.speed = Number(e.target.value); });
    scrub.addEventListener('input', () => { state.playing = false; updatePlayButton(); seek(Number(scrub.value)); });
    window.addEventListener('keydown', (e) => {
      if (e.target.tagName === 'INPUT' || e.target.tagName === 'SELECT') return;
      if (e.key === ' ') { document.getElementById('play').click(); e.preventDefault(); }
      if (e.key === ',') step(-1);
      if (e.key === '.') step(1);
    });
  }

  function recordingPanel(actor, k) {
    const box = document.createElement('div');
    box.className = 'rec';
    const head = document.createElement('div');
    const sw = document.createElement('span'); sw.className = 'swatch'; sw.style.background = SWATCHES[k % SWATCHES.length];
    const vis = document.createElement('input'); vis.type = 'checkbox'; vis.checked = true;
    vis.addEventListener('change', () => { actor.robot.visible = vis.checked; actor.overlays.group.visible = vis.checked; requestRender(); });
    head.append(vis, sw, document.createTextNode(actor.rec.info.name + (k ? ' (ghost)' : '')));
    box.appendChild(head);
    const note = document.createElement('div'); note.className = 'note';
    note.textContent = actor.rec.info.rows + ' rows, ' + actor.rec.info.t0.toFixed(3) + ' to ' + actor.rec.info.t1.toFixed(3) + ' s';
    box.appendChild(note);
    if (actor.rec.info.missing.length) {
      const m = document.createElement('div'); m.className = 'missing';
      m.textContent = 'missing columns: ' + actor.rec.info.missing.join(', ');
      box.appendChild(m);
    }
    if (k > 0) {
      const label = document.createElement('label');
      const out = document.createElement('span'); out.textContent = 'offset 0.000 s';
      const range = document.createElement('input');
      const len = Math.max(state.t1 - state.t0, 1);
      Object.assign(range, { type: 'range', min: -len, max: len, step: 'any', value: 0 });
      range.addEventListener('input', () => {
        actor.offset = Number(range.value);
        out.textContent = 'offset ' + actor.offset.toFixed(3) + ' s';
        span(); plots.draw(); requestRender();
      });
      label.append(out, range);
      box.appendChild(label);
    }
    document.getElementById('recordings').appendChild(box);
  }

  // ---- drawing ----
  let renderQueued = false;
  function requestRender() { if (!renderQueued) { renderQueued = true; requestAnimationFrame(frame); } }
  let lastTime = null;
  const bench = { seconds: Number(params.get('bench') || 0), times: [], work: [], render: [], start: null };

  function renderNow() {
    const w0 = performance.now();
    for (const a of state.actors) poseActor(a);
    for (const a of state.actors) a.overlays.update(state.show);
    updateCop();
    grid.visible = state.show.grid;
    if (state.actors.length) {
      const c = state.actors[0].overlays.comWorld;
      status.com = [c.x, c.y, c.z];
    }
    if (sliderPanel.open && state.actors[0] && state.actors[0].rec && !state.manual && status.frame % 6 === 0) sliders.follow(state.actors[0].robot);
    scrub.value = state.now;
    clock.textContent = (live.frame && !state.t1 ? live.frame.t : state.now).toFixed(3) + ' s';
    plots.moveCursor();
    controls.update();
    const r0 = performance.now();
    renderer.render(scene, camera);
    if (bench.seconds > 0) { bench.render.push(performance.now() - r0); bench.work.push(performance.now() - w0); }
    live.drawn();
    status.frame++;
  }

  function frame(ts) {
    renderQueued = false;
    if (lastTime !== null && state.playing) {
      state.now += (ts - lastTime) / 1000 * state.speed;
      if (state.now >= state.t1) { state.now = state.t1; state.playing = bench.seconds > 0; if (!state.playing) updatePlayButton(); }
    }
    lastTime = ts;
    renderNow();
    if (bench.seconds > 0 && state.playing) {
      if (bench.start === null) bench.start = ts;
      bench.times.push(ts);
      if (ts - bench.start >= bench.seconds * 1000) finishBench();
    }
    if (state.playing) requestRender();
  }

  // The rendered image itself in #snapshot (URL parameter snapshot=1), for tests:
  // independent of the browser's compositor. Live: once the first state is drawn.
  function takeSnapshot() {
    if (!params.get('snapshot') || document.getElementById('snapshot')) return;
    const pre = document.createElement('pre');
    pre.id = 'snapshot'; pre.hidden = true;
    pre.textContent = renderer.domElement.toDataURL('image/png');
    document.body.appendChild(pre);
    status.canvas = [renderer.domElement.width, renderer.domElement.height];
    publish();
  }

  function finishBench() {
    state.playing = false;
    const d = [];
    for (let i = 1; i < bench.times.length; i++) d.push(bench.times[i] - bench.times[i - 1]);
    d.sort((a, b) => a - b);
    const q = (p) => d[Math.min(d.length - 1, Math.floor(p * d.length))];
    const work = bench.work.slice().sort((a, b) => a - b);
    status.bench = {
      frames: d.length, median_ms: q(0.5), p95_ms: q(0.95),
      fps: d.length / ((bench.times[bench.times.length - 1] - bench.times[0]) / 1000),
      // Time the page spends per frame: poses, overlays, plot cursor, and issuing the draw calls.
      work_median_ms: work[Math.floor(work.length / 2)],
      render_median_ms: bench.render.slice().sort((a, b) => a - b)[bench.render.length >> 1],
    };
    bench.seconds = 0;
    publish();
  }

  // ---- start ----
  async function main() {
    resize();
    const [info, urdf] = await Promise.all([data.scene(), data.urdf()]);
    state.info = info; state.urdf = urdf;
    document.getElementById('title').textContent = info.robot + ' (' + info.joints.length + ' joints, ' + info.total_mass.toFixed(3) + ' kg)';
    document.title = info.robot + ' - twinloop view';
    for (const w of info.warnings) warn(w);
    const recs = await Promise.all(info.recordings.map(async (_, i) => {
      const [rinfo, buffer] = await Promise.all([data.recordingInfo(i), data.recordingData(i)]);
      const cols = columnViews(rinfo, buffer);
      const jointCols = info.joints.map((j) => cols['q:' + j.name] || null);
      return { info: rinfo, cols, jointCols };
    }));
    const count = Math.max(recs.length, 1);
    const robots = await Promise.all(Array.from({ length: count }, () => buildRobot(urdf)));
    robots.forEach((robot, k) => {
      const colour = k === 0 ? null : GHOST_COLOURS[k % GHOST_COLOURS.length] || 0x1e88e5;
      paint(robot, colour);
      scene.add(robot);
      const rec = recs[k] || null;
      if (rec) rec.copSources = k === 0 ? copSources(rec) : [];
      state.actors.push({ robot, rec, offset: 0, colour, sample: 0, overlays: makeOverlays(robot, info, colour) });
    });
    // A recording without a base, or none at all: stand the robot on the ground at
    // its first pose.
    for (const a of state.actors) {
      poseActor(a);
      if (a.rec && a.rec.info.has_base) continue;
      visualBox(a.robot, tmpBox);
      if (Number.isFinite(tmpBox.min.z)) a.robot.position.z = -tmpBox.min.z;
    }
    status.recordings = recs.map((r) => ({ name: r.info.name, rows: r.info.rows, missing: r.info.missing }));
    for (const r of recs) {
      if (r.info.missing.length) warn(r.info.name + ': missing columns ' + r.info.missing.join(', ') + ' (those joints stay at 0)');
    }
    sliders.build(info.joints);
    if (params.has('pose')) sliders.set(params.get('pose'));
    if (recs.length) {
      document.getElementById('no-recordings').hidden = true;
      span();
      state.now = state.t0;
      bindTimeline();
      state.actors.forEach((a, k) => { if (a.rec) recordingPanel(a, k); });
    } else if (info.live) {
      live.connect();
    } else {
      document.getElementById('sliders').open = true;
      state.manual = true;
    }
    for (const input of document.querySelectorAll('[data-overlay]')) {
      if (params.has('overlays')) input.checked = params.get('overlays').split(',').includes(input.dataset.overlay);
      state.show[input.dataset.overlay] = input.checked;
      input.addEventListener('change', () => { state.show[input.dataset.overlay] = input.checked; requestRender(); });
    }
    // Camera: from the URL, or framing the robot.
    if (params.has('t')) seek(Number(params.get('t')));
    poseActor(state.actors[0]);
    visualBox(state.actors[0].robot, tmpBox);
    const centre = tmpBox.getCenter(new THREE.Vector3());
    const size = tmpBox.getSize(new THREE.Vector3()).length() || 1;
    const cam = (params.get('camera') || '').split(',').map(Number);
    if (cam.length === 6 && cam.every(Number.isFinite)) {
      camera.position.set(cam[0], cam[1], cam[2]);
      controls.target.set(cam[3], cam[4], cam[5]);
    } else {
      // Far enough that the bounding sphere fits the narrower side of the view.
      const half = Math.tan(THREE.MathUtils.degToRad(camera.fov) / 2);
      const dist = 0.55 * size / (half * Math.min(1, camera.aspect));
      controls.target.copy(centre);
      camera.position.copy(centre).addScaledVector(new THREE.Vector3(1, -1, 0.45).normalize(), dist);
    }
    plots.build();
    resize(); plots.resize();
    if (bench.seconds > 0 && recs.length) { state.now = state.t0; state.playing = true; }
    renderNow();
    status.ready = true;
    status.load_ms = performance.now();
    if (!info.live) takeSnapshot();
    publish();
    if (state.playing) requestRender();
  }

  controls.addEventListener('change', () => requestRender());
  main().catch((e) => { console.error('twinloop view: ' + (e && e.stack || e)); });
})();
