/* appell view: the page's script. It reads the run that tools/view_page.c embedded (the
 * #appell-data JSON: base64 doubles), builds the three.js scene (bodies as their shapes with
 * markings, visual-only shapes, triads, the ground, grid and axes, contact traces, force arrows),
 * plays the frames (play, pause, scrub, speed, loop, follow a body), and draws the plots with a
 * cursor and the run record's events. World z is up. Frame i shows row i of the CSV exactly (no
 * interpolation). window.appellView exposes the state for tests and benchmarks. */
(function () {
  'use strict';
  var D = JSON.parse(document.getElementById('appell-data').textContent);

  function f64(b64) {
    var s = atob(b64), u = new Uint8Array(s.length);
    for (var i = 0; i < s.length; i++) u[i] = s.charCodeAt(i);
    return new Float64Array(u.buffer);
  }

  var nf = D.nf, nb = D.nb, T = f64(D.t), P = f64(D.pose), C = f64(D.contact);
  var F = D.forces ? f64(D.forces) : null;
  var t0 = T[0], t1 = T[nf - 1];
  var record = null, recordNote = '';
  if (D.record !== null) {
    try { record = JSON.parse(D.record); } catch (e) { recordNote = 'run record unreadable'; }
  }
  var events = record && Array.isArray(record.events) ? record.events.filter(function (e) {
    return e && typeof e.t === 'number' && isFinite(e.t);
  }) : [];

  /* ---- extent of the motion: camera, ground, grid ---- */
  var lo = [Infinity, Infinity, Infinity], hi = [-Infinity, -Infinity, -Infinity];
  function grow(x, y, z) {
    var p = [x, y, z];
    for (var k = 0; k < 3; k++) { lo[k] = Math.min(lo[k], p[k]); hi[k] = Math.max(hi[k], p[k]); }
  }
  for (var i = 0; i < nf * nb; i++) grow(P[7 * i], P[7 * i + 1], P[7 * i + 2]);
  grow(0, 0, 0);
  var bodySize = 0;
  D.bodies.forEach(function (b) {
    var s = b.shape, v = b.visual;
    bodySize = Math.max(bodySize, s.radius + s.tube, s.axes[0], s.axes[1], s.axes[2],
      v.size[0], v.size[1], v.size[2], v.radius + v.length / 2 + Math.abs(v.at[0]) +
      Math.abs(v.at[1]) + Math.abs(v.at[2]));
  });
  if (!(bodySize > 0)) bodySize = 0.2;
  var span = Math.max(hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2], 2 * bodySize, 0.5);
  var centre = new THREE.Vector3((lo[0] + hi[0]) / 2, (lo[1] + hi[1]) / 2, Math.max(0, lo[2]));
  /* The size of the mechanism itself (its bodies at frame 0): when the motion goes much farther
   * than that, the camera follows body 0 from a distance that shows the mechanism. */
  var c0 = [Infinity, Infinity, Infinity, -Infinity, -Infinity, -Infinity];
  for (i = 0; i < nb; i++)
    for (var k = 0; k < 3; k++) {
      c0[k] = Math.min(c0[k], P[7 * i + k]); c0[3 + k] = Math.max(c0[3 + k], P[7 * i + k]);
    }
  var size = Math.max(c0[3] - c0[0], c0[4] - c0[1], c0[5] - c0[2]) + 2 * bodySize;
  var followFirst = span > 4 * size;
  if (followFirst) {
    span = 1.6 * size;
    centre.set(P[0], P[1], Math.max(0, P[2]));
  }

  /* ---- renderer, camera, controls ---- */
  var host = document.getElementById('view3d');
  var renderer = new THREE.WebGLRenderer({ antialias: true });
  renderer.setPixelRatio(window.devicePixelRatio || 1);
  renderer.setClearColor(0xdfe6ee);
  host.appendChild(renderer.domElement);
  var camera = new THREE.PerspectiveCamera(40, 1, span * 1e-2, span * 100);
  camera.up.set(0, 0, 1);
  camera.position.set(centre.x + 1.1 * span, centre.y - 1.5 * span, centre.z + 0.9 * span);
  var controls = new THREE.OrbitControls(camera, renderer.domElement);
  controls.target.copy(centre);
  controls.update();

  var scene = new THREE.Scene();
  scene.add(new THREE.AmbientLight(0xffffff, 0.55));
  var sun = new THREE.DirectionalLight(0xffffff, 0.75);
  sun.position.set(0.6, -0.8, 1.5);
  scene.add(sun);

  /* ---- the grounds (D.grounds: the planes normal . p = offset and the fixed spheres the
   * contacts roll on; the plane z = 0 when there is none) ---- */
  var groundMat = new THREE.MeshLambertMaterial({ color: 0xf2f0ea, polygonOffset: true,
    polygonOffsetFactor: 2, polygonOffsetUnits: 2 });
  var gridMat = new THREE.LineBasicMaterial({ color: 0x9098a4 });
  /* A plane: the ground square and the grid in the plane's axes t1, t2 (t1 x t2 = n), placed
   * by the matrix [t1 t2 n | offset n]; for z = 0, t1 = x and t2 = y. */
  function drawPlane(g) {
    var n = new THREE.Vector3().fromArray(g.normal).normalize();
    var a = Math.abs(n.x) < 0.9 ? new THREE.Vector3(1, 0, 0) : new THREE.Vector3(0, 1, 0);
    var t1 = a.addScaledVector(n, -a.dot(n)).normalize(), t2 = new THREE.Vector3().crossVectors(n, t1);
    var ulo = [0, 0], uhi = [0, 0];
    for (var i = 0; i < nf * nb; i++) {
      var p = new THREE.Vector3(P[7 * i], P[7 * i + 1], P[7 * i + 2]), u = [p.dot(t1), p.dot(t2)];
      for (var k = 0; k < 2; k++) { ulo[k] = Math.min(ulo[k], u[k]); uhi[k] = Math.max(uhi[k], u[k]); }
    }
    var grp = new THREE.Group();
    grp.matrixAutoUpdate = false;
    grp.matrix.makeBasis(t1, t2, n).setPosition(n.clone().multiplyScalar(g.offset));
    var half = Math.ceil(Math.max(uhi[0] - ulo[0], uhi[1] - ulo[1], span) * 1.5 + 1);
    var ground = new THREE.Mesh(new THREE.PlaneGeometry(4 * half, 4 * half), groundMat);
    ground.position.z = -5e-3 * span;
    grp.add(ground);
    /* The grid: lines every `step` over the motion and a margin, each line cut into segments
     * of one step (a long line that crosses the camera's near plane is dropped by some
     * software GL rasterizers). At most 120 cells a side. */
    var step = Math.pow(10, Math.round(Math.log10(span / 3)));
    var gx0 = ulo[0] - span, gx1 = uhi[0] + span, gy0 = ulo[1] - span, gy1 = uhi[1] + span;
    while (Math.max(gx1 - gx0, gy1 - gy0) / step > 120) step *= 2;
    gx0 = step * Math.floor(gx0 / step), gy0 = step * Math.floor(gy0 / step);
    var ncx = Math.ceil((gx1 - gx0) / step), ncy = Math.ceil((gy1 - gy0) / step), seg = [];
    for (var a2 = 0; a2 <= ncx; a2++)
      for (var b2 = 0; b2 < ncy; b2++)
        seg.push(gx0 + a2 * step, gy0 + b2 * step, 0, gx0 + a2 * step, gy0 + (b2 + 1) * step, 0);
    for (b2 = 0; b2 <= ncy; b2++)
      for (a2 = 0; a2 < ncx; a2++)
        seg.push(gx0 + a2 * step, gy0 + b2 * step, 0, gx0 + (a2 + 1) * step, gy0 + b2 * step, 0);
    var gridGeo = new THREE.BufferGeometry();
    gridGeo.setAttribute('position', new THREE.BufferAttribute(new Float32Array(seg), 3));
    var grid = new THREE.LineSegments(gridGeo, gridMat);
    grid.position.z = -1e-3 * span;
    grp.add(grid);
    ground.position.x = (gx0 + gx1) / 2, ground.position.y = (gy0 + gy1) / 2;
    scene.add(grp);
    return { kind: 'plane', object: grp, surface: ground, grid: grid };
  }
  /* A sphere: seen from inside (a bowl) its far wall is drawn (BackSide), from outside (a
   * dome) its near one; parallels and meridians every 15 degrees show its curvature. */
  function drawSphere(g) {
    var geo = new THREE.SphereGeometry(g.radius, 96, 48);
    geo.rotateX(Math.PI / 2);   /* poles on the world z axis */
    var mat = groundMat.clone();
    mat.side = g.inside ? THREE.BackSide : THREE.FrontSide;
    var mesh = new THREE.Mesh(geo, mat);
    mesh.position.fromArray(g.center);
    var lines = new THREE.SphereGeometry(g.radius * (g.inside ? 0.998 : 1.002), 24, 12);
    lines.rotateX(Math.PI / 2);
    mesh.add(new THREE.LineSegments(new THREE.EdgesGeometry(lines, 1), gridMat));
    scene.add(mesh);
    return { kind: 'sphere', object: mesh, surface: mesh };
  }
  /* A height field z = h(x, y): the grid of samples (null where h is undefined) as a lit mesh,
   * both sides drawn, with grid lines every 10 samples following the surface. */
  function drawField(g) {
    var pos = [], idx = [], lines = [], nx = g.nx, ny = g.ny;
    for (var j = 0; j < ny; j++)
      for (var i = 0; i < nx; i++) {
        var z = g.z[j * nx + i];
        pos.push(g.x0 + i * g.d, g.y0 + j * g.d, z === null ? 0 : z);
      }
    function ok(i, j) { return g.z[j * nx + i] !== null; }
    for (j = 0; j + 1 < ny; j++)
      for (i = 0; i + 1 < nx; i++) {
        var a = j * nx + i;
        if (ok(i, j) && ok(i + 1, j) && ok(i, j + 1) && ok(i + 1, j + 1))
          idx.push(a, a + 1, a + nx + 1, a, a + nx + 1, a + nx);
        if (j % 10 === 0 && ok(i, j) && ok(i + 1, j)) lines.push(a, a + 1);
        if (i % 10 === 0 && ok(i, j) && ok(i, j + 1)) lines.push(a, a + nx);
      }
    var geo = new THREE.BufferGeometry();
    geo.setAttribute('position', new THREE.BufferAttribute(new Float32Array(pos), 3));
    geo.setIndex(idx);
    geo.computeVertexNormals();
    var mat = groundMat.clone();
    mat.side = THREE.DoubleSide;
    var mesh = new THREE.Mesh(geo, mat);
    var lgeo = new THREE.BufferGeometry();
    lgeo.setAttribute('position', geo.getAttribute('position'));
    lgeo.setIndex(lines);
    mesh.add(new THREE.LineSegments(lgeo, gridMat));
    scene.add(mesh);
    return { kind: 'heightfield', object: mesh, surface: mesh };
  }
  var grounds = (D.grounds && D.grounds.length ? D.grounds :
    [{ kind: 'plane', normal: [0, 0, 1], offset: 0 }]).map(function (g) {
    return g.kind === 'sphere' ? drawSphere(g) : g.kind === 'heightfield' ? drawField(g) :
      drawPlane(g);
  });
  var axes = new THREE.AxesHelper(Math.max(0.3 * span, bodySize));
  scene.add(axes);

  /* ---- bodies ---- */
  var palette = [0x3b6fb6, 0xd08a2c, 0x4c9a5b, 0x9b59b6, 0xc0392b, 0x16a085, 0x7f8c8d,
    0xb7950b];
  function mat(color, opacity) {
    var m = new THREE.MeshLambertMaterial({ color: color, side: THREE.DoubleSide });
    if (opacity < 1) { m.transparent = true; m.opacity = opacity; }
    return m;
  }
  var dark = mat(0x202020, 1), red = mat(0xe03020, 1), white = mat(0xffffff, 1);

  function wheel(g, r, width, color, rim) {
    var disk = new THREE.CylinderGeometry(r, r, width, 64);
    disk.rotateX(Math.PI / 2);
    g.add(new THREE.Mesh(disk, mat(color, 1)));
    if (rim) g.add(new THREE.Mesh(new THREE.TorusGeometry(r, rim, 16, 64), mat(0x303030, 1)));
    for (var k = 0; k < 3; k++) {   /* spokes on both faces; spoke 0 red: rotation shows */
      var sp = new THREE.BoxGeometry(2 * r * 0.96, r * 0.07, width * 1.4);
      sp.rotateZ(k * Math.PI / 3);
      g.add(new THREE.Mesh(sp, k ? white : red));
    }
    var hub = new THREE.CylinderGeometry(r * 0.1, r * 0.1, width * 1.6, 24);
    hub.rotateX(Math.PI / 2);
    g.add(new THREE.Mesh(hub, dark));
  }

  function ball(g, ax, color) {
    var s = new THREE.Mesh(new THREE.SphereGeometry(1, 48, 24), mat(color, 1));
    s.scale.set(ax[0], ax[1], ax[2]);
    g.add(s);
    var mer = new THREE.TorusGeometry(1.003, 0.035, 8, 64);
    mer.rotateX(Math.PI / 2);   /* the meridian in the body xz plane */
    var m1 = new THREE.Mesh(mer, red);
    m1.scale.set(ax[0], ax[1], ax[2]);
    g.add(m1);
    var eq = new THREE.Mesh(new THREE.TorusGeometry(1.003, 0.025, 8, 64), dark);
    eq.scale.set(ax[0], ax[1], ax[2]);
    g.add(eq);
  }

  function visual(g, v, color) {
    var geo = null;
    if (v.kind === 'box') geo = new THREE.BoxGeometry(v.size[0], v.size[1], v.size[2]);
    if (v.kind === 'sphere') geo = new THREE.SphereGeometry(v.radius, 32, 16);
    if (v.kind === 'capsule') {
      var c = new THREE.Group(), m = mat(color, 0.6);
      c.add(new THREE.Mesh(new THREE.CylinderGeometry(v.radius, v.radius, v.length, 32), m));
      [-1, 1].forEach(function (s) {
        var cap = new THREE.Mesh(new THREE.SphereGeometry(v.radius, 32, 16), m);
        cap.position.y = s * v.length / 2;
        c.add(cap);
      });
      if (v.axis === 0) c.rotation.z = -Math.PI / 2;
      if (v.axis === 2) c.rotation.x = Math.PI / 2;
      c.position.set(v.at[0], v.at[1], v.at[2]);
      g.add(c);
      return;
    }
    if (!geo) return;
    var mesh = new THREE.Mesh(geo, mat(color, 0.6));
    mesh.position.set(v.at[0], v.at[1], v.at[2]);
    g.add(mesh);
  }

  var groups = D.bodies.map(function (b, k) {
    var g = new THREE.Group(), s = b.shape, color = palette[k % palette.length];
    g.name = b.name;
    if (s.kind === 'disk') wheel(g, s.radius, Math.max(0.04 * s.radius, 0.004), color, 0);
    else if (s.kind === 'torus') wheel(g, s.radius, 0.5 * s.tube, color, s.tube);
    else if (s.kind === 'sphere') ball(g, [s.radius, s.radius, s.radius], color);
    else if (s.kind === 'ellipsoid') ball(g, s.axes, color);
    visual(g, b.visual, color);
    if (s.kind === 'none' || s.kind === 'point')
      g.add(new THREE.AxesHelper(Math.max(0.25 * bodySize, 0.02 * span)));
    scene.add(g);
    return g;
  });

  /* ---- contact traces and force arrows ---- */
  var traces = D.bodies.map(function (b, k) {
    if (!b.contact) return null;
    var xyz = new Float32Array(3 * nf);
    for (var r = 0; r < nf; r++)
      for (var c = 0; c < 3; c++) xyz[3 * r + c] = C[3 * (r * nb + k) + c];
    var geo = new THREE.BufferGeometry();
    geo.setAttribute('position', new THREE.BufferAttribute(xyz, 3));
    var line = new THREE.Line(geo, new THREE.LineBasicMaterial({ color: 0x1a1a1a }));
    line.frustumCulled = false;
    scene.add(line);
    return line;
  });
  var fmax = 0;
  if (F) for (i = 0; i < F.length; i += 3)
    fmax = Math.max(fmax, Math.hypot(F[i], F[i + 1], F[i + 2]));
  var arrows = D.bodies.map(function (b) {
    if (!b.force || !(fmax > 0)) return null;
    var a = new THREE.ArrowHelper(new THREE.Vector3(0, 0, 1), new THREE.Vector3(), 1, 0xcc2200);
    scene.add(a);
    return a;
  });

  /* ---- plots (2-D canvases) ---- */
  var side = document.getElementById('side');
  if (!D.plots.length) side.className = 'noplots';
  var plots = D.plots.map(function (p) {
    var box = document.createElement('div'), name = document.createElement('div');
    var cv = document.createElement('canvas');
    box.className = 'plot';
    name.className = 'name';
    name.textContent = p.name;
    box.appendChild(name);
    box.appendChild(cv);
    document.getElementById('plots').appendChild(box);
    return { name: p.name, y: f64(p.data), canvas: cv, bg: null };
  });

  function drawPlotBackground(p) {
    var cv = p.canvas, w = cv.clientWidth || 320, h = cv.clientHeight || 130;
    cv.width = w, cv.height = h;
    var bg = document.createElement('canvas');
    bg.width = w, bg.height = h;
    var g = bg.getContext('2d'), ymin = Infinity, ymax = -Infinity;
    for (var r = 0; r < nf; r++) if (isFinite(p.y[r])) {
      ymin = Math.min(ymin, p.y[r]); ymax = Math.max(ymax, p.y[r]);
    }
    if (!(ymax > ymin)) { ymax = (isFinite(ymax) ? ymax : 0) + 1; ymin = ymax - 2; }
    var L = 8, R = w - 4, top = 14, bot = h - 14;
    p.x = function (t) { return L + (R - L) * (t - t0) / ((t1 - t0) || 1); };
    var Y = function (y) { return bot - (bot - top) * (y - ymin) / (ymax - ymin); };
    g.fillStyle = '#fff'; g.fillRect(0, 0, w, h);
    g.strokeStyle = '#ccd'; g.strokeRect(L, top, R - L, bot - top);
    g.fillStyle = '#555'; g.font = '10px monospace';
    g.fillText(ymax.toPrecision(4), L + 2, top - 3);
    g.fillText(ymin.toPrecision(4), L + 2, h - 3);
    g.fillText(t1.toPrecision(4) + ' s', R - 50, h - 3);
    events.forEach(function (e) {
      g.strokeStyle = '#d22'; g.setLineDash([3, 3]); g.beginPath();
      g.moveTo(p.x(e.t), top); g.lineTo(p.x(e.t), bot); g.stroke(); g.setLineDash([]);
    });
    g.strokeStyle = '#2a5db0'; g.lineWidth = 1.2; g.beginPath();
    var pen = false;
    for (r = 0; r < nf; r++) {
      if (!isFinite(p.y[r])) { pen = false; continue; }
      if (pen) g.lineTo(p.x(T[r]), Y(p.y[r])); else g.moveTo(p.x(T[r]), Y(p.y[r]));
      pen = true;
    }
    g.stroke();
    p.bg = bg;
  }

  function drawPlotCursor(p, t) {
    var g = p.canvas.getContext('2d');
    g.drawImage(p.bg, 0, 0);
    g.strokeStyle = '#111'; g.beginPath();
    g.moveTo(p.x(t), 2); g.lineTo(p.x(t), p.canvas.height - 2); g.stroke();
  }

  /* ---- timeline, controls ---- */
  var scrub = document.getElementById('scrub'), playBtn = document.getElementById('play');
  var timeLabel = document.getElementById('time'), speedSel = document.getElementById('speed');
  var loopBox = document.getElementById('loop'), followSel = document.getElementById('follow');
  scrub.max = String(nf - 1);
  [0.1, 0.25, 0.5, 1, 2, 5, 10].forEach(function (s) {
    var o = document.createElement('option');
    o.value = String(s); o.textContent = s + 'x'; if (s === 1) o.selected = true;
    speedSel.appendChild(o);
  });
  D.bodies.forEach(function (b, k) {
    var o = document.createElement('option');
    o.value = String(k); o.textContent = b.name;
    followSel.appendChild(o);
  });
  var marks = document.getElementById('marks');
  events.forEach(function (e) {
    var m = document.createElement('div'), label = document.createElement('span');
    m.className = 'event-mark';
    m.dataset.name = String(e.name);
    m.dataset.t = String(e.t);
    m.style.left = (100 * (e.t - t0) / ((t1 - t0) || 1)) + '%';
    m.title = e.name + ' at t = ' + e.t;
    label.textContent = e.name;
    m.appendChild(label);
    m.addEventListener('click', function () { setTime(e.t); });
    marks.appendChild(m);
  });
  var info = document.getElementById('info');
  (function () {
    var h = '<b></b><br>' + nf + ' frames, t = ' + t0 + ' .. ' + t1 + ' s, ' + nb + ' bodies';
    info.innerHTML = h;
    info.firstChild.textContent = D.scene;
    if (record && record.status !== undefined) {
      var st = document.createElement('div');
      st.className = 'status';
      st.textContent = 'status: ' + String(record.status);
      info.appendChild(st);
    }
    if (events.length) {
      var ev = document.createElement('div');
      ev.className = 'events';
      ev.textContent = 'events: ';
      events.forEach(function (e) {
        var s = document.createElement('span');
        s.textContent = e.name + ' (t = ' + e.t + ') ';
        ev.appendChild(s);
      });
      info.appendChild(ev);
    }
    if (recordNote) info.appendChild(document.createTextNode(recordNote));
    var help = document.createElement('div');
    help.textContent = 'drag: orbit, wheel: zoom, right drag: pan, space: play/pause';
    info.appendChild(help);
  })();

  /* ---- state and frames ---- */
  var state = { frame: 0, time: t0, playing: false, speed: 1, loop: true,
    follow: followFirst ? 0 : -1 };
  var last = new THREE.Vector3(P[0], P[1], P[2]);
  followSel.value = String(state.follow);

  function frameAt(t) {   /* the last frame with T[i] <= t */
    var a = 0, b = nf - 1;
    if (t >= T[b]) return b;
    while (b - a > 1) { var m = (a + b) >> 1; if (T[m] <= t) a = m; else b = m; }
    return a;
  }

  function showFrame(k) {
    k = Math.max(0, Math.min(nf - 1, k | 0));
    state.frame = k;
    for (var b = 0; b < nb; b++) {
      var o = 7 * (k * nb + b), g = groups[b];
      g.position.set(P[o], P[o + 1], P[o + 2]);
      g.quaternion.set(P[o + 4], P[o + 5], P[o + 6], P[o + 3]);
      g.updateMatrixWorld(true);
      if (traces[b]) traces[b].geometry.setDrawRange(0, k + 1);
      if (arrows[b]) {
        var c = 3 * (k * nb + b), f = new THREE.Vector3(F[c], F[c + 1], F[c + 2]);
        var len = f.length();
        arrows[b].position.set(C[c], C[c + 1], C[c + 2]);
        arrows[b].visible = len > 0;
        if (len > 0) {
          arrows[b].setDirection(f.divideScalar(len));
          arrows[b].setLength(0.3 * span * len / fmax, 0.03 * span, 0.015 * span);
        }
      }
    }
    if (state.follow >= 0) {
      var p = groups[state.follow].position;
      camera.position.add(new THREE.Vector3().subVectors(p, last));
      controls.target.copy(p);
      last.copy(p);
    }
    scrub.value = String(k);
    timeLabel.textContent = 't = ' + T[k].toFixed(3) + ' s';
    plots.forEach(function (p) { if (p.bg) drawPlotCursor(p, T[k]); });
  }

  /* Show row k; playback goes on from its time. */
  function setFrame(k) {
    k = Math.max(0, Math.min(nf - 1, k | 0));
    state.time = T[k];
    showFrame(k);
  }

  function setTime(t) { state.time = t; showFrame(frameAt(t)); }

  function play(on) {
    state.playing = on;
    playBtn.textContent = on ? 'pause' : 'play';
    if (on && state.frame >= nf - 1) state.time = t0;
  }

  playBtn.addEventListener('click', function () { play(!state.playing); });
  scrub.addEventListener('input', function () {
    setFrame(Number(scrub.value));
  });
  speedSel.addEventListener('change', function () { state.speed = Number(speedSel.value); });
  loopBox.addEventListener('change', function () { state.loop = loopBox.checked; });
  followSel.addEventListener('change', function () {
    state.follow = Number(followSel.value);
    if (state.follow >= 0) last.copy(groups[state.follow].position);
  });
  window.addEventListener('keydown', function (e) {
    if (e.code === 'Space' && e.target.tagName !== 'SELECT') { play(!state.playing); e.preventDefault(); }
  });

  function resize() {
    var w = host.clientWidth || 400, h = host.clientHeight || 300;
    renderer.setSize(w, h);
    camera.aspect = w / h;
    camera.updateProjectionMatrix();
    plots.forEach(drawPlotBackground);
    plots.forEach(function (p) { drawPlotCursor(p, T[state.frame]); });
  }
  window.addEventListener('resize', resize);

  function render() {
    controls.update();
    renderer.render(scene, camera);
  }

  var before = null;
  function tick(now) {
    if (state.playing && before !== null) {
      state.time += state.speed * (now - before) / 1000;
      if (state.time > t1) {
        if (state.loop) state.time = t0 + (state.time - t1) % ((t1 - t0) || 1);
        else { state.time = t1; play(false); }
      }
      showFrame(frameAt(state.time));
    }
    before = now;
    render();
    requestAnimationFrame(tick);
  }

  resize();
  setFrame(0);
  requestAnimationFrame(tick);

  /* World point -> CSS pixel in the page (for tests). */
  function project(x, y, z) {
    camera.updateMatrixWorld();
    var v = new THREE.Vector3(x, y, z).project(camera), r = renderer.domElement.getBoundingClientRect();
    return [r.left + (v.x + 1) / 2 * r.width, r.top + (1 - v.y) / 2 * r.height];
  }

  window.appellView = {
    data: D, times: T, poses: P, contacts: C, events: events, record: record, state: state,
    bodies: groups, traces: traces, arrows: arrows, plots: plots, camera: camera,
    controls: controls, renderer: renderer, scene: scene,
    setFrame: setFrame, setTime: setTime, play: play, render: render, project: project,
    grounds: grounds
  };
})();
