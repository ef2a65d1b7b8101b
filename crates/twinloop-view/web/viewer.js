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
//
// Speed. A frame's work does not grow with the recording: the row shown is found
// from the last one (a binary search after a jump), the robot is posed and its CoM
// and support polygon computed only when that row changes, nothing is allocated per
// frame, and the clock, scrub bar, plot cursor and sliders follow playback at 10 Hz
// (each DOM change costs the browser a layout and a repaint). The visual meshes of
// each link are merged into one draw call: software WebGL pays for every call.
'use strict';
(function () {
  const { THREE, OrbitControls, STLLoader, OBJLoader, ColladaLoader, URDFLoader, uPlot } = window.TL;
  const EMBED = window.TWINLOOP_EMBED || null;
  const params = new URLSearchParams(location.search);
  const GHOST_COLOURS = [null, 0x1e88e5, 0xe53935, 0x43a047, 0x8e24aa];
  const SWATCHES = ['#9e9e9e', '#1e88e5', '#e53935', '#43a047', '#8e24aa'];
  const GRAVITY = 9.81;
  const CONTACT_HEIGHT = 0.01; // m: geometry this close to the ground counts as touching it
  const UI_PERIOD_MS = 100; // the clock, scrub bar, plot cursor and sliders during playback
  const COP_WEIGHT_LENGTH = 0.4; // m: the ground-reaction arrow of the robot's weight

  // ---- status for people (banner) and for tests (#status JSON) ----
  // `com`, `overlays` and `timeline` are computed when read (JSON.stringify reads
  // them): nothing is built per frame for them.
  const safe = (f) => { try { return f(); } catch (e) { return null; } };
  const status = {
    ready: false, errors: [], warnings: [], recordings: [], frame: 0, antialias: null,
    get com() { return safe(() => comOf(0)); },
    get overlays() { return safe(overlayReport); },
    get timeline() { return safe(timelineReport); },
  };
  window.twinloop = status;
  const statusEl = document.getElementById('status');
  const scrub = document.getElementById('scrub');
  const clock = document.getElementById('clock');
  const sliderPanel = document.getElementById('sliders');
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

  // ---- one draw call per link ----
  // Software WebGL pays for every draw call (measured in headless Chromium: km20's
  // 133 visual meshes took 5 ms of CPU a frame), so each link's visual meshes are
  // merged into one geometry in the link's frame, coloured per vertex. Meshes with
  // a texture or a translucent material keep their own draw call.
  const tmpMat = new THREE.Matrix4(), tmpInv = new THREE.Matrix4(), tmpNormalMat = new THREE.Matrix3();
  const tmpV = new THREE.Vector3(), tmpN = new THREE.Vector3();

  // The meshes drawn for `link` itself (not for the links below its joints).
  function ownMeshes(link) {
    const out = [];
    const walk = (o) => {
      for (const c of o.children) {
        if (c.isURDFJoint || c.userData.overlay) continue;
        if (c.isMesh) out.push(c);
        walk(c);
      }
    };
    walk(link);
    return out;
  }
  function mergeable(m) {
    const mat = m.material;
    return !Array.isArray(mat) && !mat.map && !mat.transparent && !m.isSkinnedMesh && !m.isInstancedMesh &&
      m.geometry.attributes.position && (m.geometry.index ? m.geometry.index.count : m.geometry.attributes.position.count) % 3 === 0;
  }
  // One geometry: the triangles of `parts`, placed by `toLink` (each part's pose in
  // the link frame), with normals and the colour of each part's material. Indexed,
  // as most parts are: shared corners are shaded once.
  function mergeGeometry(parts, toLink) {
    const geoms = parts.map((m) => {
      let g = m.geometry;
      if (!g.attributes.normal) { g = g.clone(); g.computeVertexNormals(); }
      return g;
    });
    let nv = 0, ni = 0;
    for (const g of geoms) { nv += g.attributes.position.count; ni += g.index ? g.index.count : g.attributes.position.count; }
    const pos = new Float32Array(3 * nv), nor = new Float32Array(3 * nv), col = new Float32Array(3 * nv);
    const index = nv > 65535 ? new Uint32Array(ni) : new Uint16Array(ni);
    let v0 = 0, k = 0;
    parts.forEach((m, i) => {
      const g = geoms[i], p = g.attributes.position, n = g.attributes.normal, c = m.material.color;
      tmpMat.copy(toLink[i]);
      tmpNormalMat.getNormalMatrix(tmpMat);
      for (let v = 0; v < p.count; v++) {
        const o = 3 * (v0 + v);
        tmpV.fromBufferAttribute(p, v).applyMatrix4(tmpMat);
        tmpN.fromBufferAttribute(n, v).applyMatrix3(tmpNormalMat).normalize();
        pos[o] = tmpV.x; pos[o + 1] = tmpV.y; pos[o + 2] = tmpV.z;
        nor[o] = tmpN.x; nor[o + 1] = tmpN.y; nor[o + 2] = tmpN.z;
        col[o] = c.r; col[o + 1] = c.g; col[o + 2] = c.b;
      }
      // A mirroring placement turns the triangles inside out: swap two corners back.
      const flip = tmpMat.determinant() < 0;
      const idx = g.index, count = idx ? idx.count : p.count;
      for (let t = 0; t < count; t += 3) {
        const a = idx ? idx.getX(t) : t, b = idx ? idx.getX(t + 1) : t + 1, d = idx ? idx.getX(t + 2) : t + 2;
        index[k++] = v0 + a; index[k++] = v0 + (flip ? d : b); index[k++] = v0 + (flip ? b : d);
      }
      v0 += p.count;
    });
    const g = new THREE.BufferGeometry();
    g.setAttribute('position', new THREE.BufferAttribute(pos, 3));
    g.setAttribute('normal', new THREE.BufferAttribute(nor, 3));
    g.setAttribute('color', new THREE.BufferAttribute(col, 3));
    g.setIndex(new THREE.BufferAttribute(index, 1));
    g.computeBoundingBox();
    g.computeBoundingSphere();
    return g;
  }

  // Make a robot ready to draw: its links' meshes merged (solid: coloured as the
  // description says; a ghost, `colour` not null: translucent in that colour), and
  // for each link the corners of its visuals' bounding boxes in the link frame (for
  // the support polygon and to stand the robot on the ground).
  function prepareRobot(robot, colour) {
    robot.updateMatrixWorld(true);
    const ghost = colour !== null;
    const shared = ghost
      ? new THREE.MeshPhongMaterial({ color: colour, transparent: true, opacity: 0.35, depthWrite: false })
      : new THREE.MeshPhongMaterial({ vertexColors: true });
    const links = [];
    robot.traverse((o) => { if (o.isURDFLink) links.push(o); });
    const drawn = new Map(); // link -> [{ mesh, base (material or colour) }]
    const corners = [];      // { link, local: Float64Array of x, y, z }
    for (const link of links) {
      const meshes = ownMeshes(link);
      if (!meshes.length) continue;
      tmpInv.copy(link.matrixWorld).invert();
      const toLink = meshes.map((m) => new THREE.Matrix4().multiplyMatrices(tmpInv, m.matrixWorld));
      const local = new Float64Array(24 * meshes.length);
      meshes.forEach((m, i) => {
        if (!m.geometry.boundingBox) m.geometry.computeBoundingBox();
        const b = m.geometry.boundingBox;
        for (let c = 0; c < 8; c++) {
          tmpV.set(c & 1 ? b.max.x : b.min.x, c & 2 ? b.max.y : b.min.y, c & 4 ? b.max.z : b.min.z).applyMatrix4(toLink[i]);
          local[24 * i + 3 * c] = tmpV.x; local[24 * i + 3 * c + 1] = tmpV.y; local[24 * i + 3 * c + 2] = tmpV.z;
        }
      });
      corners.push({ link, local });
      const merge = [], mergeTo = [], list = [];
      meshes.forEach((m, i) => {
        if (mergeable(m)) { merge.push(m); mergeTo.push(toLink[i]); m.parent.remove(m); return; }
        // Kept as it is: its own material (translucent in the ghost's colour).
        const mat = (Array.isArray(m.material) ? m.material[0] : m.material).clone();
        if (ghost) Object.assign(mat, { transparent: true, opacity: 0.35, depthWrite: false }).color = new THREE.Color(colour);
        m.material = mat;
        list.push({ mesh: m, base: mat.color.clone() });
      });
      if (merge.length) {
        const mesh = new THREE.Mesh(mergeGeometry(merge, mergeTo), shared);
        mesh.userData.merged = true;
        link.add(mesh);
        list.push({ mesh, base: shared });
      }
      drawn.set(link, list);
    }
    robot.updateMatrixWorld(true);
    return { drawn, corners };
  }
  const LIMIT_MATERIAL = new THREE.MeshPhongMaterial({ color: 0xd32f2f });

  // World corners of every visual's bounding box, into `out` (x, y, z; grown once).
  function worldCorners(corners, out) {
    let k = 0;
    for (const { link, local } of corners) {
      const e = link.matrixWorld.elements;
      for (let i = 0; i < local.length; i += 3) {
        const x = local[i], y = local[i + 1], z = local[i + 2];
        out[k++] = e[0] * x + e[4] * y + e[8] * z + e[12];
        out[k++] = e[1] * x + e[5] * y + e[9] * z + e[13];
        out[k++] = e[2] * x + e[6] * y + e[10] * z + e[14];
      }
    }
    return k / 3;
  }
  function cornerCount(corners) { return corners.reduce((n, c) => n + c.local.length / 3, 0); }
  // The world bounding box of a robot's visual geometry (the corners of its visuals'
  // boxes; not its overlays).
  function visualBox(actor, box) {
    box.makeEmpty();
    const n = worldCorners(actor.corners, actor.cornerBuf);
    for (let i = 0; i < n; i++) box.expandByPoint(tmpV.set(actor.cornerBuf[3 * i], actor.cornerBuf[3 * i + 1], actor.cornerBuf[3 * i + 2]));
    return box;
  }
  const tmpBox = new THREE.Box3();

  // Andrew's monotone chain: the convex hull of the points (hx[i], hy[i]) for i in
  // `idx[0..n)`, counter-clockwise, as indices into `hull` (room for 2n); returns its
  // length. Works in the arrays given (no allocation).
  let hx = null, hy = null;
  const byXY = (a, b) => hx[a] - hx[b] || hy[a] - hy[b];
  const cross = (o, a, b) => (hx[a] - hx[o]) * (hy[b] - hy[o]) - (hy[a] - hy[o]) * (hx[b] - hx[o]);
  function convexHull(xs, ys, idx, n, hull) {
    hx = xs; hy = ys;
    const sub = idx.subarray(0, n);
    sub.sort(byXY);
    if (n < 3) { for (let i = 0; i < n; i++) hull[i] = sub[i]; return n; }
    let k = 0;
    for (let i = 0; i < n; i++) {
      while (k >= 2 && cross(hull[k - 2], hull[k - 1], sub[i]) <= 0) k--;
      hull[k++] = sub[i];
    }
    for (let i = n - 2, lower = k + 1; i >= 0; i--) {
      while (k >= lower && cross(hull[k - 2], hull[k - 1], sub[i]) <= 0) k--;
      hull[k++] = sub[i];
    }
    return k - 1;
  }

  // ---- overlays of one robot ----
  // The CoM and support polygon are computed when the robot's pose changes, the
  // visibility of each overlay when a checkbox changes: a frame that shows the same
  // row again costs nothing here.
  function makeOverlays(actor, info, colour) {
    const robot = actor.robot;
    const group = new THREE.Group();
    scene.add(group);
    const tint = colour === null ? 0xd32f2f : colour;
    const com = new THREE.Mesh(new THREE.SphereGeometry(0.015, 16, 12), new THREE.MeshBasicMaterial({ color: tint }));
    const comGround = new THREE.Mesh(new THREE.CircleGeometry(0.012, 24), new THREE.MeshBasicMaterial({ color: tint }));
    // The plumb line from the CoM: positions and dash distances written in place.
    const comLineGeom = new THREE.BufferGeometry();
    const comLinePos = new THREE.BufferAttribute(new Float32Array(6), 3);
    const comLineDist = new THREE.BufferAttribute(new Float32Array(2), 1);
    comLineGeom.setAttribute('position', comLinePos);
    comLineGeom.setAttribute('lineDistance', comLineDist);
    const comLine = new THREE.Line(comLineGeom, new THREE.LineDashedMaterial({ color: tint, dashSize: 0.01, gapSize: 0.01 }));
    // One fixed buffer for the polygon, room for every corner (a new attribute each
    // time would leak GPU buffers).
    const nCorners = Math.max(cornerCount(actor.corners), 1);
    const supportGeom = new THREE.BufferGeometry();
    const supportPos = new THREE.BufferAttribute(new Float32Array(3 * nCorners), 3);
    supportPos.setUsage(THREE.DynamicDrawUsage);
    supportGeom.setAttribute('position', supportPos);
    supportGeom.setDrawRange(0, 0);
    const support = new THREE.LineLoop(supportGeom, new THREE.LineBasicMaterial({ color: colour === null ? 0x2e7d32 : colour }));
    const comGroup = new THREE.Group();
    comGroup.add(com, comGround, comLine);
    // Drawn over the robot: the CoM is inside the body. Their geometry moves, so
    // their bounding spheres would be stale: never culled.
    for (const o of [com, comGround, comLine, support]) { o.material.depthTest = false; o.renderOrder = 10; }
    comLine.frustumCulled = false;
    support.frustumCulled = false;
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
      frames.push({ link: l.name, obj: axes });
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
        boxes.push({ link: l.name, obj: box });
      }
    }
    const totalMass = massive.reduce((s, m) => s + m.mass, 0);
    const comWorld = new THREE.Vector3();
    // Scratch for the support polygon, sized once.
    const buf = actor.cornerBuf;
    const xs = new Float64Array(nCorners), ys = new Float64Array(nCorners);
    const idx = new Uint32Array(nCorners), hull = new Uint32Array(2 * nCorners + 2);
    let hullN = 0, supportStale = true, shownVersion = -1;
    return {
      group, comGroup, support, frames, boxes, comWorld,
      hull() { const out = []; for (let i = 0; i < hullN; i++) out.push([xs[hull[i]], ys[hull[i]]]); return out; },
      // `posed`: the robot moved since the last call.
      update(show, posed) {
        if (shownVersion !== state.showVersion) {
          shownVersion = state.showVersion;
          comGroup.visible = show.com;
          support.visible = show.support;
          for (const f of frames) f.obj.visible = show.frames;
          for (const b of boxes) b.obj.visible = show.inertia;
        }
        if (posed) {
          comWorld.set(0, 0, 0);
          for (const m of massive) comWorld.addScaledVector(tmpV.copy(m.com).applyMatrix4(m.link.matrixWorld), m.mass);
          if (totalMass > 0) comWorld.multiplyScalar(1 / totalMass);
          com.position.copy(comWorld);
          comGround.position.set(comWorld.x, comWorld.y, 0.001);
          comLinePos.setXYZ(0, comWorld.x, comWorld.y, comWorld.z);
          comLinePos.setXYZ(1, comWorld.x, comWorld.y, 0);
          comLinePos.needsUpdate = true;
          comLineDist.setX(1, Math.abs(comWorld.z));
          comLineDist.needsUpdate = true;
          supportStale = true;
        }
        if (show.support && supportStale) {
          supportStale = false;
          const n = worldCorners(actor.corners, buf);
          let m = 0;
          for (let i = 0; i < n; i++) {
            if (buf[3 * i + 2] < CONTACT_HEIGHT) { xs[m] = buf[3 * i]; ys[m] = buf[3 * i + 1]; idx[m] = m; m++; }
          }
          hullN = convexHull(xs, ys, idx, m, hull);
          for (let i = 0; i < hullN; i++) supportPos.setXYZ(i, xs[hull[i]], ys[hull[i]], 0.002);
          supportPos.needsUpdate = true;
          supportGeom.setDrawRange(0, hullN);
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
  // The last sample at or before time t (the first if t is earlier). Playback moves
  // on by a row or a few from the last one found (`hint`): looked at first, so a
  // frame costs the same for 100 rows or 100 000; a jump is a binary search.
  function sampleAt(t, times, hint) {
    const last = times.length - 1;
    if (t <= times[0]) return 0;
    if (t >= times[last]) return last;
    let lo = 0, hi = last;
    if (hint > 0 && hint < last && times[hint] <= t) {
      for (let k = 0; k < 8; k++, hint++) if (times[hint + 1] > t) return hint;
      lo = hint;
    }
    while (hi - lo > 1) {
      const mid = (lo + hi) >> 1;
      if (times[mid] <= t) lo = mid; else hi = mid;
    }
    return lo;
  }

  const state = {
    info: null, urdf: null,
    actors: [],          // see main(): robot, rec|null, offset, colour, sample, joints, overlays, ...
    now: 0, t0: 0, t1: 0, playing: false, speed: 1, manual: false,
    show: { grid: true, com: true, support: true, cop: true, limits: true, frames: false, inertia: false },
    showVersion: 0,
  };
  const LIMIT_COLOUR = new THREE.Color(0xd32f2f);

  // Pose `actor` for the current time (its recording's row), the live state or the
  // sliders; false when that is the pose it already has.
  function poseActor(actor) {
    const { robot, rec, joints } = actor;
    const info = state.info.joints;
    if (rec && !state.manual) {
      const i = sampleAt(state.now - actor.offset, rec.cols.t, actor.sample);
      actor.sample = i;
      if (actor.posedBy === 'rec' && actor.posed === i) return false;
      actor.posedBy = 'rec'; actor.posed = i;
      for (let j = 0; j < info.length; j++) {
        const col = rec.jointCols[j];
        if (joints[j]) joints[j].setJointValue(col ? col[i] : 0);
      }
      if (rec.base) {
        const b = rec.base;
        robot.position.set(b[0][i], b[1][i], b[2][i]);
        robot.quaternion.set(b[3][i], b[4][i], b[5][i], b[6][i]).normalize();
      }
    } else if (actor === state.actors[0] && live.frame && !state.manual) {
      if (actor.posedBy === 'live' && actor.posed === live.seq) return false;
      actor.posedBy = 'live'; actor.posed = live.seq;
      live.apply(actor);
    } else if (actor === state.actors[0]) {
      if (actor.posedBy === 'sliders' && actor.posed === sliders.version) return false;
      actor.posedBy = 'sliders'; actor.posed = sliders.version;
      sliders.apply(actor);
    } else {
      return false;
    }
    robot.updateMatrixWorld(true);
    if (state.show.limits && actor.colour === null) colourLimits(actor);
    return true;
  }

  // A link's drawn meshes in the limit colour, or back in their own.
  function paintLink(actor, link, red) {
    const list = link && actor.drawn.get(link);
    if (!list) return;
    for (const d of list) {
      if (d.mesh.userData.merged) d.mesh.material = red ? LIMIT_MATERIAL : d.base;
      else d.mesh.material.color.copy(red ? LIMIT_COLOUR : d.base);
    }
  }
  function colourLimits(actor) {
    for (const l of actor.limited) {
      const v = l.joint.angle;
      const atLimit = v <= l.lower + l.tol || v >= l.upper - l.tol;
      if (atLimit === l.atLimit) continue;
      l.atLimit = atLimit;
      paintLink(actor, l.link, atLimit);
    }
  }
  function clearLimits(actor) {
    for (const l of actor.limited) if (l.atLimit) { l.atLimit = false; paintLink(actor, l.link, false); }
  }
  // The joints with both limits, and the link each moves.
  function limitedJoints(robot) {
    const out = [];
    for (const j of state.info.joints) {
      const joint = robot.joints[j.name];
      if (!joint || j.lower === null || j.upper === null) continue;
      out.push({
        name: j.name, joint, lower: j.lower, upper: j.upper, atLimit: false,
        tol: Math.max(1e-3 * (j.upper - j.lower), 1e-4),
        link: joint.children.find((c) => c.isURDFLink) || null,
      });
    }
    return out;
  }

  // Centre of pressure and ground reaction arrows from foot:* or grf/cop columns.
  const copGroup = new THREE.Group();
  scene.add(copGroup);
  function copSources(rec) {
    const out = [];
    for (const name of rec.info.columns) {
      const m = /^foot:(.+)\.fz$/.exec(name);
      if (m && rec.cols['foot:' + m[1] + '.cop.x'] && rec.cols['foot:' + m[1] + '.cop.y']) {
        out.push({ name: 'foot:' + m[1], fz: rec.cols[name], x: rec.cols['foot:' + m[1] + '.cop.x'], y: rec.cols['foot:' + m[1] + '.cop.y'] });
      }
    }
    if (rec.cols['grf.fz'] && rec.cols['cop.x'] && rec.cols['cop.y']) {
      out.push({ name: 'grf', fz: rec.cols['grf.fz'], fx: rec.cols['grf.fx'], fy: rec.cols['grf.fy'], x: rec.cols['cop.x'], y: rec.cols['cop.y'] });
    }
    return out.map((s) => {
      const arrow = new THREE.ArrowHelper(new THREE.Vector3(0, 0, 1), new THREE.Vector3(), 0.1, 0x00897b, 0.02, 0.012);
      // Drawn through the foot and leg it starts inside.
      for (const part of [arrow.line, arrow.cone]) { part.material.depthTest = false; part.renderOrder = 11; }
      arrow.visible = false;
      copGroup.add(arrow);
      return Object.assign(s, { arrow, force: new THREE.Vector3() });
    });
  }
  function updateCop() {
    copGroup.visible = state.show.cop;
    const main = state.actors[0];
    if (!main || !main.rec || !state.show.cop) return;
    const i = main.sample;
    const scale = COP_WEIGHT_LENGTH / Math.max(state.info.total_mass * GRAVITY, 1);
    for (const s of main.rec.copSources) {
      const fz = s.fz[i];
      s.force.set(s.fx ? s.fx[i] : 0, s.fy ? s.fy[i] : 0, fz);
      const on = fz > 0.5 && Number.isFinite(s.x[i]) && Number.isFinite(s.y[i]);
      s.arrow.visible = on;
      if (!on) continue;
      s.arrow.position.set(s.x[i], s.y[i], 0.003);
      s.arrow.setDirection(tmpN.copy(s.force).normalize());
      s.arrow.setLength(Math.max(s.force.length() * scale, 0.02), 0.02, 0.012);
    }
  }

  // ---- what the page shows, for tests (read when #status is written) ----
  function shown(obj) {
    for (let p = obj; p; p = p.parent) if (!p.visible) return false;
    return true;
  }
  const xyz = (v) => [v.x, v.y, v.z];
  function comOf(k) {
    const a = state.actors[k];
    return a ? xyz(a.overlays.comWorld) : null;
  }
  function overlayReport() {
    const a = state.actors[0];
    if (!a) return null;
    const o = a.overlays;
    const world = (obj) => xyz(obj.getWorldPosition(new THREE.Vector3()));
    return {
      on: Object.assign({}, state.show),
      grid: shown(grid),
      com: shown(o.comGroup) ? xyz(o.comWorld) : null,
      support: shown(o.support) ? o.hull() : [],
      cop: (a.rec ? a.rec.copSources : []).map((s) => ({
        name: s.name, shown: shown(s.arrow), at: xyz(s.arrow.position), force: xyz(s.force),
        direction: xyz(new THREE.Vector3(0, 1, 0).applyQuaternion(s.arrow.quaternion)),
        length: s.arrow.cone.position.y,
      })),
      limits: a.limited.filter((l) => l.atLimit).map((l) => l.name),
      limit_coloured: a.limited.filter((l) => l.link && (a.drawn.get(l.link) || []).some((d) => d.mesh.material === LIMIT_MATERIAL || (d.mesh.material.color && d.mesh.material.color.equals(LIMIT_COLOUR)))).map((l) => l.name),
      frames: o.frames.filter((f) => shown(f.obj)).map((f) => ({ link: f.link, at: world(f.obj) })),
      inertia: o.boxes.filter((b) => shown(b.obj)).map((b) => {
        const g = b.obj.geometry;
        if (!g.boundingBox) g.computeBoundingBox();
        return { link: b.link, at: world(b.obj), size: xyz(g.boundingBox.getSize(new THREE.Vector3())) };
      }),
    };
  }
  function timelineReport() {
    return {
      now: state.now, t0: state.t0, t1: state.t1, playing: state.playing, speed: state.speed, manual: state.manual,
      actors: state.actors.map((a) => ({
        offset: a.offset, sample: a.sample,
        t: a.rec ? a.rec.cols.t[a.sample] : null,
        base: xyz(a.robot.position),
      })),
      // When `now` was computed (the animation frame's time, ms).
      frame_time: lastTime,
      plot: plots.u ? plots.u.series.slice(1).map((s, k) => {
        const ys = plots.u.data[k + 1];
        return { label: s.label, n: ys.length, first: ys[0], last: ys[ys.length - 1] };
      }) : [],
      clock: clock.textContent, scrub: Number(scrub.value),
    };
  }

  // ---- live: the newest state of a running source, over a websocket ----
  // While connected the page draws on every animation frame with the newest state
  // (the server sends a little faster than the screen, so almost every frame has a
  // new one); lags are kept in fixed rings and summarised only when read.
  const LAG_RING = 600;
  const live = {
    frame: null, seq: 0, frames: 0, connected: false,
    drawnSeq: 0, drawnT: null, drawnSent: 0, fresh: 0, drawnFrames: 0,
    lags: new Float64Array(LAG_RING), nLags: 0,
    recvLags: new Float64Array(LAG_RING), nRecv: 0,
    scratch: new Float64Array(LAG_RING),
    connect() {
      const ws = new WebSocket((location.protocol === 'https:' ? 'wss://' : 'ws://') + location.host + '/live');
      ws.onopen = () => { this.connected = true; requestRender(); };
      ws.onmessage = (e) => {
        this.frame = JSON.parse(e.data);
        this.seq++;
        this.frames++;
        // Lag on arrival (server and network) apart from lag on screen (plus the
        // wait for the browser's next frame and the drawing).
        this.recvLags[this.nRecv++ % LAG_RING] = Date.now() - this.frame.sent_ms;
        requestRender();
      };
      ws.onclose = () => {
        this.connected = false;
        warn('live view: the connection closed (the source stopped or the server ended)');
      };
      document.getElementById('no-recordings').textContent = 'live';
    },
    apply(actor) {
      const f = this.frame, joints = actor.joints;
      for (let j = 0; j < joints.length; j++) {
        const v = f.q[j];
        if (v !== null && v !== undefined && joints[j]) joints[j].setJointValue(v);
      }
      const b = f.base;
      if (b && b[0] !== null && b[1] !== null && b[2] !== null && b[3] !== null && b[4] !== null && b[5] !== null && b[6] !== null) {
        actor.robot.position.set(b[0], b[1], b[2]);
        actor.robot.quaternion.set(b[3], b[4], b[5], b[6]).normalize();
      }
    },
    // Called once a frame is drawn: the lag of a state drawn for the first time,
    // from the publisher's clock.
    drawn() {
      if (!this.frame) return;
      this.drawnFrames++;
      if (this.drawnSeq === this.seq) return;
      this.drawnSeq = this.seq;
      this.drawnT = this.frame.t;
      this.fresh++;
      this.lags[this.nLags++ % LAG_RING] = Date.now() - this.frame.sent_ms;
      if (this.fresh === 1 || this.fresh % 30 === 0) publish();
      takeSnapshot();
    },
    // Quantile p of the last LAG_RING values of a ring.
    quantiles(ring, n) {
      const m = Math.min(n, LAG_RING);
      const s = this.scratch.subarray(0, m);
      s.set(ring.subarray(0, m));
      s.sort();
      return (p) => m ? s[Math.min(m - 1, Math.floor(p * m))] : null;
    },
    report() {
      if (!this.frame) return null;
      const d = this.quantiles(this.lags, this.nLags);
      const out = { frames: this.frames, t: this.drawnT, fresh: this.fresh, drawn: this.drawnFrames,
        lag_median_ms: d(0.5), lag_p95_ms: d(0.95), lag_max_ms: d(1) };
      const r = this.quantiles(this.recvLags, this.nRecv);
      Object.assign(out, { recv_lag_median_ms: r(0.5), recv_lag_p95_ms: r(0.95), recv_lag_max_ms: r(1) });
      return out;
    },
  };
  Object.defineProperty(status, 'live', { enumerable: true, get: () => safe(() => live.report()) });

  // ---- joint sliders ----
  const sliders = {
    inputs: [], version: 0,
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
          state.manual = true; setPlaying(false);
          val.textContent = Number(input.value).toFixed(3);
          this.version++;
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
      this.version++;
    },
    apply(actor) {
      const joints = actor.robot.joints;
      for (const s of this.inputs) if (joints[s.joint]) joints[s.joint].setJointValue(Number(s.input.value));
    },
    // The sliders show the replayed pose (called at the UI rate, when open).
    follow(actor) {
      for (const s of this.inputs) {
        const j = actor.robot.joints[s.joint];
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
    u: null, cursor: null, xs: null, cursorPx: null,
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
      this.cursorPx = null;
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
        let hint = 0;
        const ys = a === base ? col : Float64Array.from(xs, (x) => col[hint = sampleAt(x - a.offset, a.rec.cols.t, hint)]);
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
      const px = Math.round(10 * this.u.valToPos(state.now, 'x')) / 10;
      if (px === this.cursorPx) return;
      this.cursorPx = px;
      this.cursor.style.left = px + 'px';
    },
    resize() {
      if (this.u) { this.u.setSize({ width: Math.max(document.getElementById('plot').clientWidth, 300), height: 180 }); this.cursorPx = null; }
    },
  };

  // ---- timeline ----
  function setPlaying(on) {
    if (state.playing === on) return;
    state.playing = on;
    // Time runs from the next frame on: a pause is not played through.
    lastTime = null;
    document.getElementById('play').innerHTML = on ? '&#10074;&#10074;' : '&#9654;';
    uiStale = true;
  }
  function span() {
    let t0 = Infinity, t1 = -Infinity;
    for (const a of state.actors) if (a.rec) { t0 = Math.min(t0, a.rec.info.t0 + a.offset); t1 = Math.max(t1, a.rec.info.t1 + a.offset); }
    state.t0 = Number.isFinite(t0) ? t0 : 0; state.t1 = Number.isFinite(t1) ? t1 : 0;
    scrub.min = state.t0; scrub.max = state.t1;
  }
  function seek(t) {
    state.manual = false;
    state.now = Math.min(Math.max(t, state.t0), state.t1);
    uiStale = true;
    requestRender();
  }
  function step(direction) {
    const main = state.actors.find((a) => a.rec);
    if (!main) return;
    setPlaying(false);
    const times = main.rec.cols.t;
    const i = sampleAt(state.now - main.offset, times, main.sample);
    const j = Math.min(Math.max(i + direction, 0), times.length - 1);
    seek(times[j] + main.offset);
  }
  function bindTimeline() {
    document.getElementById('timeline').hidden = false;
    document.getElementById('play').addEventListener('click', () => {
      if (!state.playing && state.now >= state.t1) state.now = state.t0;
      state.manual = false; setPlaying(!state.playing); requestRender();
    });
    document.getElementById('step-back').addEventListener('click', () => step(-1));
    document.getElementById('step-fwd').addEventListener('click', () => step(1));
    document.getElementById('speed').addEventListener('change', (e) => { state.speed = Number(e.target.value); });
    scrub.addEventListener('input', () => { setPlaying(false); seek(Number(scrub.value)); });
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
      range.className = 'offset';
      const len = Math.max(state.t1 - state.t0, 1);
      Object.assign(range, { type: 'range', min: -len, max: len, step: 'any', value: 0 });
      range.addEventListener('input', () => {
        actor.offset = Number(range.value);
        out.textContent = 'offset ' + actor.offset.toFixed(3) + ' s';
        span(); plots.draw(); uiStale = true; requestRender();
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
  // The clock, scrub bar, plot cursor and sliders: at UI_PERIOD_MS while playing,
  // at once after a seek, a step or a pause.
  let uiStale = true, uiAt = -Infinity, clockText = '';
  function updateUi(ts) {
    if (!uiStale && ts - uiAt < UI_PERIOD_MS) return;
    uiStale = false; uiAt = ts;
    if (state.t1 > state.t0) scrub.value = state.now;
    const text = (live.frame && !state.t1 ? live.drawnT || 0 : state.now).toFixed(3) + ' s';
    if (text !== clockText) clock.textContent = clockText = text;
    plots.moveCursor();
    const main = state.actors[0];
    if (sliderPanel.open && main && (main.rec || live.frame) && !state.manual) sliders.follow(main);
  }

  function renderNow(ts) {
    const w0 = performance.now();
    let moved = false;
    for (const a of state.actors) {
      const posed = poseActor(a);
      a.overlays.update(state.show, posed);
      if (posed && a === state.actors[0]) moved = true;
    }
    if (moved || copShown !== state.showVersion) { copShown = state.showVersion; updateCop(); }
    grid.visible = state.show.grid;
    updateUi(ts);
    controls.update();
    const r0 = performance.now();
    renderer.render(scene, camera);
    if (bench.seconds > 0) { bench.render.push(performance.now() - r0); bench.work.push(performance.now() - w0); }
    status.frame++;
    live.drawn();
  }
  let copShown = -1;

  function frame(ts) {
    renderQueued = false;
    if (state.playing) {
      if (lastTime !== null) state.now += (ts - lastTime) / 1000 * state.speed;
      if (state.now >= state.t1) { state.now = state.t1; if (bench.seconds <= 0) setPlaying(false); }
    }
    lastTime = ts;
    renderNow(ts);
    if (bench.seconds > 0 && state.playing) {
      if (bench.start === null) bench.start = ts;
      bench.times.push(ts);
      if (ts - bench.start >= bench.seconds * 1000) finishBench();
    }
    if (state.playing || live.connected) requestRender();
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
    setPlaying(false);
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
      const base = rinfo.has_base ? ['x', 'y', 'z', 'qx', 'qy', 'qz', 'qw'].map((c) => cols['q:base.' + c]) : null;
      return { info: rinfo, cols, jointCols, base };
    }));
    const count = Math.max(recs.length, 1);
    const robots = await Promise.all(Array.from({ length: count }, () => buildRobot(urdf)));
    robots.forEach((robot, k) => {
      const colour = k === 0 ? null : GHOST_COLOURS[k % GHOST_COLOURS.length] || 0x1e88e5;
      const { drawn, corners } = prepareRobot(robot, colour);
      scene.add(robot);
      const rec = recs[k] || null;
      if (rec) rec.copSources = k === 0 ? copSources(rec) : [];
      const actor = {
        robot, rec, offset: 0, colour, sample: 0, posedBy: null, posed: null, drawn, corners,
        cornerBuf: new Float64Array(3 * Math.max(cornerCount(corners), 1)),
        joints: info.joints.map((j) => robot.joints[j.name] || null),
        limited: colour === null ? limitedJoints(robot) : [],
      };
      actor.overlays = makeOverlays(actor, info, colour);
      state.actors.push(actor);
    });
    // A recording without a base, or none at all: stand the robot on the ground at
    // its first pose.
    for (const a of state.actors) {
      poseActor(a);
      if (a.rec && a.rec.base) continue;
      visualBox(a, tmpBox);
      if (Number.isFinite(tmpBox.min.z)) { a.robot.position.z = -tmpBox.min.z; a.robot.updateMatrixWorld(true); a.posedBy = null; }
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
      input.addEventListener('change', () => {
        state.show[input.dataset.overlay] = input.checked;
        state.showVersion++;
        if (input.dataset.overlay === 'limits') {
          for (const a of state.actors) if (input.checked) colourLimits(a); else clearLimits(a);
        }
        requestRender();
      });
    }
    state.showVersion++;
    if (!state.show.limits) for (const a of state.actors) clearLimits(a);
    // Camera: from the URL, or framing the robot.
    if (params.has('t')) seek(Number(params.get('t')));
    poseActor(state.actors[0]);
    visualBox(state.actors[0], tmpBox);
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
    if (bench.seconds > 0 && recs.length) { state.now = state.t0; setPlaying(true); }
    // The first drawing poses every robot and computes its overlays anew.
    for (const a of state.actors) a.posedBy = null;
    renderNow(performance.now());
    status.ready = true;
    status.load_ms = performance.now();
    if (!info.live) takeSnapshot();
    publish();
    if (state.playing) requestRender();
  }

  controls.addEventListener('change', () => requestRender());
  main().catch((e) => { console.error('twinloop view: ' + (e && e.stack || e)); });
})();
