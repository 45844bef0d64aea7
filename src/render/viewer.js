// tensegrity-fmu run viewer: a self-contained canvas-2D perspective view of a recorded run.
// Reads the run from the JSON element with id "run-data"; loads nothing else.
(function () {
  "use strict";

  var D = JSON.parse(document.getElementById("run-data").textContent);
  // The bulk comes as base64 of little-endian typed arrays (see html.rs): node pairs as
  // u32, per-frame values as f32 flattened over frames. Each frame becomes a view.
  function decode(b64) {
    var s = atob(b64), bytes = new Uint8Array(s.length);
    for (var i = 0; i < s.length; i++) bytes[i] = s.charCodeAt(i);
    return bytes.buffer;
  }
  function pairs(b64) {
    var a = new Uint32Array(decode(b64)), out = new Array(a.length >> 1);
    for (var i = 0; i < out.length; i++) out[i] = [a[2 * i], a[2 * i + 1]];
    return out;
  }
  function perFrame(b64, width) {
    var a = new Float32Array(decode(b64)), out = [];
    for (var k = 0; k < D.times.length; k++) out.push(a.subarray(k * width, (k + 1) * width));
    return out;
  }
  D.bars = pairs(D.bars);
  D.cables = pairs(D.cables);
  D.positions = perFrame(D.positions, 3 * D.n_nodes);
  D.velocities = perFrame(D.velocities, 3 * D.n_nodes);
  D.tensions = perFrame(D.tensions, D.cables.length);
  D.bar_forces = perFrame(D.bar_forces, D.bars.length);
  // Contacts (when recorded): frame k's points and forces, each a flat [x, y, z, …].
  var CONTACTS = null;
  if (D.contacts) {
    CONTACTS = { frames: [], maxForce: D.contacts.max_force, perNewton: D.contacts.metres_per_newton };
    var counts = new Uint32Array(decode(D.contacts.counts));
    var cp = new Float32Array(decode(D.contacts.points)), cf = new Float32Array(decode(D.contacts.forces));
    for (var ck = 0, at = 0; ck < counts.length; at += 3 * counts[ck], ck++) {
      CONTACTS.frames.push({ points: cp.subarray(at, at + 3 * counts[ck]), forces: cf.subarray(at, at + 3 * counts[ck]) });
    }
  }
  var N = D.n_nodes, NB = D.bars.length, NC = D.cables.length, NF = D.times.length;

  var STYLE = {
    background: "#f4f6f9",
    bar: "#2d3440",            // rgb(45, 52, 64)
    barHighlight: "#e8590c",
    node: "#2d3440",
    pinned: "#c92a2a",
    pointMass: "#7b2fbf",
    slack: "#96a0b0",            // rgb(150, 160, 176)
    ground: "rgba(120, 134, 107, 0.18)",
    groundLine: "rgba(90, 104, 80, 0.35)",
    // Terrain base colours before shading (as in the PNG pictures).
    terrain: { plane: [226, 222, 205], box: [200, 162, 118], heightfield: [142, 180, 122] },
    highlight: "#e8590c",
    contact: "#c814a0"          // rgb(200, 20, 160), as in the PNG pictures
  };
  // Cable colour ramp: tension 0 → max (blue, cyan, green, orange, red).
  var RAMP = [
    [0.0, [49, 99, 206]],
    [0.25, [23, 162, 184]],
    [0.5, [64, 160, 43]],
    [0.75, [240, 140, 0]],
    [1.0, [214, 40, 40]]
  ];

  function num(v) { return (v === null || v === undefined || !isFinite(v)) ? NaN : v; }

  // ---- run statistics -------------------------------------------------------------------
  var lo = [Infinity, Infinity, Infinity], hi = [-Infinity, -Infinity, -Infinity];
  var maxTension = 0;
  for (var k = 0; k < NF; k++) {
    var P = D.positions[k];
    for (var i = 0; i < N; i++) {
      for (var c = 0; c < 3; c++) {
        var v = num(P[3 * i + c]);
        if (v < lo[c]) lo[c] = v;
        if (v > hi[c]) hi[c] = v;
      }
    }
    var T = D.tensions[k];
    for (var j = 0; j < NC; j++) {
      var t = num(T[j]);
      if (t > maxTension) maxTension = t;
    }
  }
  if (!(lo[0] <= hi[0])) { lo = [-1, -1, -1]; hi = [1, 1, 1]; }
  var center0 = [(lo[0] + hi[0]) / 2, (lo[1] + hi[1]) / 2, (lo[2] + hi[2]) / 2];
  var radius = Math.max(1e-6, 0.5 * Math.hypot(hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]));
  if (maxTension <= 0) maxTension = 1;
  // Typical member length (median of the bars' start lengths, else of all members): sets
  // the drawn thickness so a tall tower of short bars is not drawn as one blob.
  var memberLength = (function () {
    var list = (NB ? D.bars : D.cables).map(function (e) {
      var P = D.positions[0] || [];
      return Math.hypot(num(P[3 * e[1]]) - num(P[3 * e[0]]), num(P[3 * e[1] + 1]) - num(P[3 * e[0] + 1]),
                        num(P[3 * e[1] + 2]) - num(P[3 * e[0] + 2]));
    }).filter(function (l) { return l > 0; }).sort(function (a, b) { return a - b; });
    return list.length ? Math.min(list[list.length >> 1], 2 * radius) : radius;
  })();
  var pinned = {}, masses = {};
  D.pinned.forEach(function (n) { pinned[n] = true; });
  D.point_masses.forEach(function (n) { masses[n] = true; });

  // ---- vectors ---------------------------------------------------------------------------
  function sub(a, b) { return [a[0] - b[0], a[1] - b[1], a[2] - b[2]]; }
  function add(a, b) { return [a[0] + b[0], a[1] + b[1], a[2] + b[2]]; }
  function mul(a, s) { return [a[0] * s, a[1] * s, a[2] * s]; }
  function dot(a, b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
  function cross(a, b) { return [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]; }
  function unit(a) { var l = Math.hypot(a[0], a[1], a[2]) || 1; return [a[0] / l, a[1] / l, a[2] / l]; }

  // ---- terrain ---------------------------------------------------------------------------
  // Boxes and heightfields as quads with a shade fixed by their normal (light from above,
  // a little from +x and +y); planes are drawn as the ground is.
  var LIGHT = [0.398, 0.221, 0.890];
  var TERRAIN = D.terrain || [];
  var terrainFaces = [];
  TERRAIN.forEach(function (t, shape) {
    if (t.kind === "plane") return;
    t.quads.forEach(function (q) {
      var p = q.map(function (k) { return t.points[k]; });
      var n = unit(cross(sub(p[2], p[0]), sub(p[3], p[1])));
      var lit = 0.6 + 0.4 * Math.max(0, dot(n, LIGHT));
      var rgb = STYLE.terrain[t.kind].map(function (c) { return Math.round(c * lit); });
      var edge = rgb.map(function (c) { return Math.round(c * (t.kind === "box" ? 0.6 : 0.88)); });
      terrainFaces.push({ kind: t.kind, shape: shape, corners: p, normal: n, rgb: rgb, edge: "rgb(" + edge.join(",") + ")" });
    });
  });
  var barRadius = D.bar_radius || [];

  // ---- camera (z up) ---------------------------------------------------------------------
  var FOV = 35 * Math.PI / 180;
  var cam = {};
  function resetCamera() {
    cam.yaw = -60 * Math.PI / 180;
    cam.pitch = 18 * Math.PI / 180;
    cam.dist = radius / Math.sin(FOV / 2) * 1.08;
    cam.center = center0.slice();
  }
  resetCamera();
  var basis; // {eye, r, u, f, focal, cx, cy}

  var canvas = document.getElementById("view");
  var ctx = canvas.getContext("2d");
  var W = 0, H = 0, DPR = 1;

  function updateBasis() {
    var cp = Math.cos(cam.pitch);
    var dir = [cp * Math.cos(cam.yaw), cp * Math.sin(cam.yaw), Math.sin(cam.pitch)];
    var eye = add(cam.center, mul(dir, cam.dist));
    var f = mul(dir, -1);
    var r = unit(cross(f, [0, 0, 1]));
    var u = cross(r, f);
    basis = { eye: eye, r: r, u: u, f: f, focal: 0.5 * Math.min(W, H) / Math.tan(FOV / 2), cx: W / 2, cy: H / 2 };
  }
  var NEAR = 1e-3;
  function toCam(p) {
    var d = sub(p, basis.eye);
    return [dot(d, basis.r), dot(d, basis.u), dot(d, basis.f)];
  }
  function camToScreen(q) {
    return [basis.cx + basis.focal * q[0] / q[2], basis.cy - basis.focal * q[1] / q[2], q[2]];
  }
  function project3(p) {
    var q = toCam(p);
    if (q[2] < NEAR * radius) return null;
    return camToScreen(q);
  }
  // Clip a camera-space segment to the near plane; null when wholly behind.
  function clipSeg(a, b) {
    var zn = NEAR * radius;
    if (a[2] < zn && b[2] < zn) return null;
    if (a[2] < zn) { var s = (zn - a[2]) / (b[2] - a[2]); a = add(a, mul(sub(b, a), s)); }
    if (b[2] < zn) { var s2 = (zn - b[2]) / (a[2] - b[2]); b = add(b, mul(sub(a, b), s2)); }
    return [camToScreen(a), camToScreen(b)];
  }

  // ---- state -----------------------------------------------------------------------------
  var frame = 0, playing = false, playClock = 0, lastTick = null, speed = 1;
  var hover = null, selected = null; // {kind: "node"|"bar"|"cable", index}
  var screen = []; // projected node positions of the current frame: [x, y, depth] or null
  var mouse = null;

  function pos(k, i) {
    var P = D.positions[k];
    return [num(P[3 * i]), num(P[3 * i + 1]), num(P[3 * i + 2])];
  }

  function rampColor(x) {
    if (!(x >= 0)) x = 0;
    if (x > 1) x = 1;
    for (var m = 1; m < RAMP.length; m++) {
      if (x <= RAMP[m][0]) {
        var a = RAMP[m - 1], b = RAMP[m], s = (x - a[0]) / (b[0] - a[0]);
        return "rgb(" + [0, 1, 2].map(function (c) { return Math.round(a[1][c] + s * (b[1][c] - a[1][c])); }).join(",") + ")";
      }
    }
    return "rgb(" + RAMP[RAMP.length - 1][1].join(",") + ")";
  }

  function fmt(x, digits) {
    if (!isFinite(x)) return "–";
    var a = Math.abs(x);
    if (a !== 0 && (a < 1e-3 || a >= 1e5)) return x.toExponential(2);
    return x.toFixed(digits === undefined ? 3 : digits);
  }

  // ---- drawing ---------------------------------------------------------------------------
  function resize() {
    var rect = canvas.getBoundingClientRect();
    DPR = window.devicePixelRatio || 1;
    W = Math.max(1, rect.width); H = Math.max(1, rect.height);
    canvas.width = Math.round(W * DPR); canvas.height = Math.round(H * DPR);
    draw();
  }

  // A plane `n · x = height` as a gridded quad around the view's centre.
  function drawPlane(normal, height, fill, line) {
    var n = unit(normal);
    var c0 = sub(cam.center, mul(n, dot(n, cam.center) - height));
    var a = Math.abs(n[0]) < 0.9 ? [1, 0, 0] : [0, 1, 0];
    var t1 = unit(cross(n, a)), t2 = cross(n, t1);
    var s = radius * 1.6, cells = 10;
    var corners = [[-1, -1], [1, -1], [1, 1], [-1, 1]].map(function (c) {
      return toCam(add(c0, add(mul(t1, c[0] * s), mul(t2, c[1] * s))));
    });
    if (corners.every(function (q) { return q[2] > NEAR * radius; })) {
      ctx.beginPath();
      corners.forEach(function (q, m) {
        var p = camToScreen(q);
        if (m === 0) ctx.moveTo(p[0], p[1]); else ctx.lineTo(p[0], p[1]);
      });
      ctx.closePath();
      ctx.fillStyle = fill;
      ctx.fill();
    }
    ctx.strokeStyle = line;
    ctx.lineWidth = 1;
    ctx.setLineDash([]);
    ctx.beginPath();
    for (var m = 0; m <= cells; m++) {
      var w = -s + 2 * s * m / cells;
      [[t1, t2], [t2, t1]].forEach(function (ax) {
        var seg = clipSeg(toCam(add(c0, add(mul(ax[0], w), mul(ax[1], -s)))),
                          toCam(add(c0, add(mul(ax[0], w), mul(ax[1], s)))));
        if (seg) { ctx.moveTo(seg[0][0], seg[0][1]); ctx.lineTo(seg[1][0], seg[1][1]); }
      });
    }
    ctx.stroke();
  }

  function drawGround() {
    if (D.ground) drawPlane(D.ground.normal, D.ground.height, STYLE.ground, STYLE.groundLine);
    TERRAIN.forEach(function (t) {
      if (t.kind !== "plane") return;
      var lit = 0.6 + 0.4 * Math.max(0, dot(unit(t.normal), LIGHT));
      var rgb = STYLE.terrain.plane.map(function (c) { return Math.round(c * lit); });
      drawPlane(t.normal, t.height, "rgb(" + rgb.join(",") + ")", "rgba(90, 90, 70, 0.3)");
    });
  }

  // The terrain faces seen this frame in drawing order: heightfield quads far first, each
  // box's near faces (those turned away left out) after the quads it may hide and before
  // the quads in front of one of those faces' planes (as in the PNG pictures).
  function visibleFaces() {
    var quads = [], boxes = [], byShape = {};
    terrainFaces.forEach(function (f) {
      var q = f.corners.map(toCam);
      if (!q.every(function (c) { return c[2] > NEAR * radius; })) return;
      var facing = dot(f.normal, sub(basis.eye, f.corners[0])) > 0;
      if (f.kind === "box" && !facing) return;
      var pts = q.map(camToScreen);
      var xs = pts.map(function (p) { return p[0]; }), ys = pts.map(function (p) { return p[1]; });
      var v = {
        face: f, pts: pts, facing: facing,
        depth: (q[0][2] + q[1][2] + q[2][2] + q[3][2]) / 4,
        box: [Math.min.apply(null, xs), Math.min.apply(null, ys), Math.max.apply(null, xs), Math.max.apply(null, ys)]
      };
      if (f.kind !== "box") { quads.push(v); return; }
      if (!byShape[f.shape]) { byShape[f.shape] = []; boxes.push(byShape[f.shape]); }
      byShape[f.shape].push(v);
    });
    var far = function (a, b) { return b.depth - a.depth; };
    quads.sort(far);
    var mean = function (b) { return b.reduce(function (s, v) { return s + v.depth; }, 0) / b.length; };
    boxes.sort(function (a, b) { return mean(b) - mean(a); });
    var layers = boxes.map(function () { return []; });
    layers.push([]);
    quads.forEach(function (v) {
      var c = mul(v.face.corners.reduce(add, [0, 0, 0]), 0.25), l = 0;
      boxes.forEach(function (b, i) {
        if (b.some(function (f) { return dot(f.face.normal, sub(c, f.face.corners[0])) > 0; })) l = i + 1;
      });
      layers[l].push(v);
    });
    var out = [];
    layers.forEach(function (l, i) { out = out.concat(l, boxes[i] || []); });
    return out;
  }

  function insidePoly(x, y, pts) {
    var odd = false;
    for (var k = 0, j = pts.length - 1; k < pts.length; j = k++) {
      var p = pts[k], r = pts[j];
      if ((p[1] > y) !== (r[1] > y) && x < p[0] + (y - p[1]) / (r[1] - p[1]) * (r[0] - p[0])) odd = !odd;
    }
    return odd;
  }

  // Members are judged in PIECES pieces: bit i of the mask is set when piece i lies more
  // than `tol` beyond a face's plane (seen from the eye) inside its picture. Such pieces
  // are drawn faintly over the terrain, the rest as usual.
  var PIECES = 8;
  function hiddenPieces(faces, a, b, tol) {
    var mask = 0;
    var mids = [], seen = [];
    for (var i = 0; i < PIECES; i++) {
      var p = add(a, mul(sub(b, a), (i + 0.5) / PIECES));
      mids.push(p);
      seen.push(project3(p));
    }
    faces.forEach(function (v) {
      var f = v.face, side = v.facing ? 1 : -1, c = f.corners[0];
      for (var i = 0; i < PIECES; i++) {
        var q = seen[i];
        if (!q || q[0] < v.box[0] || q[0] > v.box[2] || q[1] < v.box[1] || q[1] > v.box[3]) continue;
        if (dot(f.normal, sub(mids[i], c)) * side < -tol && insidePoly(q[0], q[1], v.pts)) {
          mask |= 1 << i;
        }
      }
    });
    return mask;
  }

  // [from, to] fractions of the pieces whose bit equals `behind`, neighbours joined.
  function stretches(mask, behind) {
    var out = [];
    for (var i = 0; i < PIECES; i++) {
      if (((mask >> i) & 1) === 1 !== behind) continue;
      var last = out[out.length - 1];
      if (last && last[1] === i / PIECES) last[1] = (i + 1) / PIECES;
      else out.push([i / PIECES, (i + 1) / PIECES]);
    }
    return out;
  }

  function drawFaces(faces) {
    faces.forEach(function (v) {
      ctx.beginPath();
      v.pts.forEach(function (p, m) { if (m === 0) ctx.moveTo(p[0], p[1]); else ctx.lineTo(p[0], p[1]); });
      ctx.closePath();
      ctx.fillStyle = "rgb(" + v.face.rgb.join(",") + ")";
      ctx.fill();
      ctx.strokeStyle = v.face.edge;
      ctx.lineWidth = 1;
      ctx.setLineDash([]);
      ctx.stroke();
    });
  }

  function isSel(kind, index) {
    return (hover && hover.kind === kind && hover.index === index) ||
           (selected && selected.kind === kind && selected.index === index);
  }

  function draw() {
    if (!W) return;
    updateBasis();
    ctx.setTransform(1, 0, 0, 1, 0, 0);
    ctx.fillStyle = STYLE.background;
    ctx.fillRect(0, 0, canvas.width, canvas.height);
    ctx.setTransform(DPR, 0, 0, DPR, 0, 0);
    drawGround();
    if (!NF || !N) {
      ctx.fillStyle = "#5c6675";
      ctx.font = "16px sans-serif";
      ctx.textAlign = "center";
      ctx.fillText("no recorded frames", W / 2, H / 2);
      ctx.textAlign = "start";
      screen = [];
      return;
    }

    var camPos = [];
    screen = [];
    for (var i = 0; i < N; i++) {
      var q = toCam(pos(frame, i));
      camPos.push(q);
      screen.push(q[2] >= NEAR * radius && isFinite(q[0] + q[1] + q[2]) ? camToScreen(q) : null);
    }
    var barWidth = memberPixels() * 0.05;
    barWidth = Math.max(2.5, Math.min(12, barWidth));
    var cableWidth = Math.max(1.6, Math.min(4, barWidth * 0.38));

    var segs = [];
    D.bars.forEach(function (b, m) { segs.push({ kind: "bar", index: m, a: b[0], b: b[1] }); });
    D.cables.forEach(function (cb, m) { segs.push({ kind: "cable", index: m, a: cb[0], b: cb[1] }); });
    segs.forEach(function (s) { s.depth = (camPos[s.a][2] + camPos[s.b][2]) / 2; });
    segs.sort(function (x, y) { return y.depth - x.depth; });
    var T = D.tensions[frame];
    var faces = visibleFaces();
    var tol = 0.04 * radius + 2 * barRadius.reduce(function (m, r) { return Math.max(m, r); }, 0);
    segs.forEach(function (s) {
      s.mask = faces.length ? hiddenPieces(faces, pos(frame, s.a), pos(frame, s.b), tol) : 0;
    });

    function drawSegs(behind) {
      ctx.lineCap = "round";
      ctx.globalAlpha = behind ? 0.3 : 1;
      segs.forEach(function (s) {
        var A = camPos[s.a], B = camPos[s.b];
        stretches(s.mask, behind).forEach(function (st) {
          var seg = clipSeg(add(A, mul(sub(B, A), st[0])), add(A, mul(sub(B, A), st[1])));
          if (!seg || !isFinite(seg[0][0] + seg[0][1] + seg[1][0] + seg[1][1])) return;
          strokeSeg(s, seg);
        });
      });
    }
    function strokeSeg(s, seg) {
      var hl = isSel(s.kind, s.index);
      ctx.beginPath();
      ctx.moveTo(seg[0][0], seg[0][1]);
      ctx.lineTo(seg[1][0], seg[1][1]);
      if (s.kind === "bar") {
        ctx.setLineDash([]);
        ctx.strokeStyle = hl ? STYLE.barHighlight : STYLE.bar;
        // A bar with a radius is drawn as thick as it is, where that is thicker.
        var r = barRadius[s.index] || 0;
        ctx.lineWidth = Math.max(barWidth, r > 0 && s.depth > 0 ? 2 * r * basis.focal / s.depth : 0);
      } else {
        var t = num(T[s.index]);
        if (!(t > 0)) {
          ctx.setLineDash([6, 5]);
          ctx.strokeStyle = hl ? STYLE.highlight : STYLE.slack;
          ctx.lineWidth = hl ? cableWidth + 1.5 : Math.max(1.4, cableWidth * 0.8);
        } else {
          ctx.setLineDash([]);
          ctx.strokeStyle = rampColor(t / maxTension);
          ctx.lineWidth = hl ? cableWidth + 2 : cableWidth;
          if (hl) {
            ctx.stroke();
            ctx.strokeStyle = STYLE.highlight;
            ctx.lineWidth = 1.5;
          }
        }
      }
      ctx.stroke();
    }
    drawFaces(faces);
    drawSegs(true);
    drawSegs(false);
    ctx.setLineDash([]);

    // Nodes, far to near. Where members are only a few pixels long (a large structure seen
    // whole), plain nodes would bury them, so only marked or highlighted ones are drawn.
    var crowded = memberPixels() < 12;
    var order = [];
    for (i = 0; i < N; i++) {
      if (screen[i] && (!crowded || pinned[i] || masses[i] || isSel("node", i))) order.push(i);
    }
    order.sort(function (x, y) { return screen[y][2] - screen[x][2]; });
    var r0 = Math.max(2.2, barWidth * 0.6);
    order.forEach(function (i) {
      var p = screen[i], hl = isSel("node", i);
      if (pinned[i]) {
        var h = r0 * 2.6;
        ctx.beginPath();
        ctx.moveTo(p[0], p[1]);
        ctx.lineTo(p[0] - h * 0.7, p[1] + h);
        ctx.lineTo(p[0] + h * 0.7, p[1] + h);
        ctx.closePath();
        ctx.fillStyle = STYLE.pinned;
        ctx.fill();
        ctx.beginPath();
        ctx.moveTo(p[0] - h, p[1] + h + 2);
        ctx.lineTo(p[0] + h, p[1] + h + 2);
        ctx.strokeStyle = STYLE.pinned;
        ctx.lineWidth = 2;
        ctx.stroke();
      }
      var rr = masses[i] ? r0 * 2 : r0;
      ctx.beginPath();
      ctx.arc(p[0], p[1], hl ? rr + 2.5 : rr, 0, 2 * Math.PI);
      ctx.fillStyle = hl ? STYLE.highlight : (masses[i] ? STYLE.pointMass : (pinned[i] ? STYLE.pinned : STYLE.node));
      ctx.fill();
      ctx.lineWidth = 1.5;
      ctx.strokeStyle = "#ffffff";
      ctx.stroke();
    });
    drawContacts();
    drawAxes();
  }

  // Contact points as dots, their forces as arrows (the run's largest 15 % of its size).
  function drawContacts() {
    var c = CONTACTS && CONTACTS.frames[frame];
    if (!c) return;
    ctx.setLineDash([]);
    ctx.strokeStyle = ctx.fillStyle = STYLE.contact;
    for (var m = 0; m < c.points.length; m += 3) {
      var p = [c.points[m], c.points[m + 1], c.points[m + 2]];
      var f = [c.forces[m], c.forces[m + 1], c.forces[m + 2]];
      var seg = clipSeg(toCam(p), toCam(add(p, mul(f, CONTACTS.perNewton))));
      if (!seg) continue;
      arrow(ctx, seg[0][0], seg[0][1], seg[1][0], seg[1][1], 2.5);
    }
    for (m = 0; m < c.points.length; m += 3) {
      var q = project3([c.points[m], c.points[m + 1], c.points[m + 2]]);
      if (!q) continue;
      ctx.beginPath();
      ctx.arc(q[0], q[1], 4, 0, 2 * Math.PI);
      ctx.fillStyle = STYLE.contact;
      ctx.fill();
      ctx.lineWidth = 1.2;
      ctx.strokeStyle = "#ffffff";
      ctx.stroke();
    }
  }

  // A line from (x0, y0) to (x1, y1) with a head there, in the current colour.
  function arrow(g, x0, y0, x1, y1, width) {
    var dx = x1 - x0, dy = y1 - y0, len = Math.hypot(dx, dy);
    if (len < 2) return;
    var ux = dx / len, uy = dy / len, head = Math.min(0.35 * len, 6 + 2 * width);
    g.lineWidth = width;
    g.beginPath(); g.moveTo(x0, y0); g.lineTo(x1 - ux * head * 0.5, y1 - uy * head * 0.5); g.stroke();
    g.beginPath();
    g.moveTo(x1, y1);
    g.lineTo(x1 - head * (ux * 0.94 - uy * 0.34), y1 - head * (uy * 0.94 + ux * 0.34));
    g.lineTo(x1 - head * (ux * 0.94 + uy * 0.34), y1 - head * (uy * 0.94 - ux * 0.34));
    g.closePath(); g.fill();
  }

  // Pixels of a typical member seen at the view's distance.
  function memberPixels() { return basis.focal / cam.dist * memberLength; }

  function drawAxes() {
    // A small orientation triad in the lower-right corner.
    var o = [W - 46, H - 46], L = 26;
    [["x", [1, 0, 0], "#c92a2a"], ["y", [0, 1, 0], "#2b8a3e"], ["z", [0, 0, 1], "#1c5fc9"]].forEach(function (ax) {
      var d = ax[1];
      var sx = dot(d, basis.r), sy = dot(d, basis.u);
      ctx.beginPath();
      ctx.moveTo(o[0], o[1]);
      ctx.lineTo(o[0] + L * sx, o[1] - L * sy);
      ctx.strokeStyle = ax[2];
      ctx.lineWidth = 2;
      ctx.stroke();
      ctx.fillStyle = ax[2];
      ctx.font = "12px sans-serif";
      ctx.fillText(ax[0], o[0] + (L + 7) * sx - 3, o[1] - (L + 7) * sy + 4);
    });
  }

  // ---- picking ---------------------------------------------------------------------------
  function segDist(px, py, a, b) {
    var dx = b[0] - a[0], dy = b[1] - a[1];
    var l2 = dx * dx + dy * dy;
    var s = l2 > 0 ? Math.max(0, Math.min(1, ((px - a[0]) * dx + (py - a[1]) * dy) / l2)) : 0;
    return [Math.hypot(px - a[0] - s * dx, py - a[1] - s * dy), a[2] + s * (b[2] - a[2])];
  }

  // The node within 9 px (nearest to the eye among ties), else the nearest bar or cable
  // within 7 px (bars first: they are drawn thick).
  function pick(px, py) {
    var best = null;
    for (var i = 0; i < N; i++) {
      var p = screen[i];
      if (!p) continue;
      var d = Math.hypot(px - p[0], py - p[1]);
      var reach = masses[i] ? 12 : 8;
      if (d <= reach && (!best || d < best.d - 2 || (Math.abs(d - best.d) <= 2 && p[2] < best.z))) {
        best = { kind: "node", index: i, d: d, z: p[2] };
      }
    }
    if (best) return { kind: best.kind, index: best.index };
    var cand = null;
    function consider(kind, list, reach) {
      list.forEach(function (e, m) {
        var a = screen[e[0]], b = screen[e[1]];
        if (!a || !b) return;
        var r = segDist(px, py, a, b);
        if (r[0] > reach) return;
        if (!cand || r[0] < cand.d - 1 || (r[0] <= cand.d + 1 && r[1] < cand.z)) {
          cand = { kind: kind, index: m, d: r[0], z: r[1] };
        }
      });
    }
    var barReach = Math.max(6, Math.max(2.5, Math.min(12, memberPixels() * 0.05)) / 2 + 2);
    consider("bar", D.bars, barReach);
    if (cand) return { kind: cand.kind, index: cand.index };
    consider("cable", D.cables, 7);
    return cand ? { kind: cand.kind, index: cand.index } : null;
  }

  function describe(sel) {
    if (!sel) return "";
    var k = frame, i = sel.index;
    if (sel.kind === "node") {
      var p = pos(k, i), V = D.velocities[k];
      var vel = V ? Math.hypot(num(V[3 * i]), num(V[3 * i + 1]), num(V[3 * i + 2])) : NaN;
      var tags = [];
      if (pinned[i]) tags.push("pinned");
      if (masses[i]) tags.push("point mass");
      return "node " + (i + 1) + (tags.length ? " (" + tags.join(", ") + ")" : "") +
        ": x = " + fmt(p[0]) + ", y = " + fmt(p[1]) + ", z = " + fmt(p[2]) + " m, |v| = " + fmt(vel) + " m/s";
    }
    if (sel.kind === "bar") {
      var b = D.bars[i], F = num(D.bar_forces[k][i]);
      var len = Math.hypot.apply(null, sub(pos(k, b[1]), pos(k, b[0])));
      return "bar " + (i + 1) + ": nodes " + (b[0] + 1) + "–" + (b[1] + 1) + ", length " + fmt(len) +
        " m, force " + fmt(F, 2) + " N (" + (F >= 0 ? "compression" : "tension") + ")";
    }
    var c = D.cables[i], t = num(D.tensions[k][i]);
    var cl = Math.hypot.apply(null, sub(pos(k, c[1]), pos(k, c[0])));
    return "cable " + (i + 1) + ": nodes " + (c[0] + 1) + "–" + (c[1] + 1) + ", length " + fmt(cl) +
      " m, " + (t > 0 ? "tension " + fmt(t, 2) + " N" : "slack (tension 0)");
  }

  var tooltip = document.getElementById("tooltip");
  var status = document.getElementById("status");
  function showInfo() {
    var sel = hover || selected;
    if (sel) {
      status.textContent = describe(sel);
    } else {
      status.textContent = "hover or click a node, bar or cable";
    }
    if (hover && mouse) {
      tooltip.textContent = describe(hover).replace(": ", "\n");
      tooltip.hidden = false;
      var x = mouse[0] + 14, y = mouse[1] + 14;
      if (x + tooltip.offsetWidth > W - 4) x = mouse[0] - 14 - tooltip.offsetWidth;
      if (y + tooltip.offsetHeight > H - 4) y = mouse[1] - 14 - tooltip.offsetHeight;
      tooltip.style.left = x + "px";
      tooltip.style.top = y + "px";
    } else {
      tooltip.hidden = true;
    }
  }

  // ---- time ------------------------------------------------------------------------------
  var slider = document.getElementById("time");
  var clock = document.getElementById("clock");
  var playButton = document.getElementById("play");
  slider.max = String(Math.max(0, NF - 1));

  function showClock() {
    var tEnd = NF ? D.times[NF - 1] : 0;
    var digits = tEnd >= 100 ? 1 : tEnd >= 10 ? 2 : 3;
    clock.textContent = "t = " + (NF ? D.times[frame].toFixed(digits) : "–") + " s / " + tEnd.toFixed(digits) + " s";
  }

  function setFrame(k) {
    k = Math.max(0, Math.min(NF - 1, Math.round(k)));
    if (!(k >= 0)) k = 0;
    frame = k;
    slider.value = String(k);
    showClock();
    draw();
    if (hover && mouse) hover = pick(mouse[0], mouse[1]);
    showInfo();
  }

  function setPlaying(on) {
    playing = on && NF > 1;
    playButton.textContent = playing ? "Pause" : "Play";
    if (playing) {
      if (frame >= NF - 1) frame = 0;
      playClock = D.times[frame];
      lastTick = null;
      requestAnimationFrame(tick);
    }
  }

  function tick(now) {
    if (!playing) return;
    if (lastTick !== null) {
      playClock += (now - lastTick) / 1000 * speed;
      var tEnd = D.times[NF - 1];
      if (playClock > tEnd) playClock = D.times[0];
      var k = frame;
      if (D.times[k] > playClock) k = 0;
      while (k + 1 < NF && D.times[k + 1] <= playClock) k++;
      if (k !== frame) setFrame(k);
    }
    lastTick = now;
    requestAnimationFrame(tick);
  }

  slider.addEventListener("input", function () { setFrame(Number(slider.value)); });
  playButton.addEventListener("click", function () { setPlaying(!playing); });
  document.getElementById("speed").addEventListener("change", function (e) { speed = Number(e.target.value) || 1; });

  // ---- pointer ---------------------------------------------------------------------------
  var drag = null;
  function local(e) {
    var r = canvas.getBoundingClientRect();
    return [e.clientX - r.left, e.clientY - r.top];
  }
  canvas.addEventListener("pointerdown", function (e) {
    var p = local(e);
    drag = { x: p[0], y: p[1], moved: false, pan: e.shiftKey || e.button === 2 };
    try { canvas.setPointerCapture(e.pointerId); } catch (err) { /* synthetic pointer */ }
  });
  canvas.addEventListener("pointermove", function (e) {
    var p = local(e);
    mouse = p;
    if (drag) {
      var dx = p[0] - drag.x, dy = p[1] - drag.y;
      if (Math.abs(dx) + Math.abs(dy) > 2) drag.moved = true;
      if (drag.moved) {
        canvas.classList.add("dragging");
        if (drag.pan) {
          var s = cam.dist / basis.focal;
          cam.center = add(cam.center, add(mul(basis.r, -dx * s), mul(basis.u, dy * s)));
        } else {
          cam.yaw -= dx * 0.008;
          cam.pitch = Math.max(-1.5, Math.min(1.5, cam.pitch + dy * 0.008));
        }
        drag.x = p[0]; drag.y = p[1];
        draw();
        return;
      }
    }
    var h = pick(p[0], p[1]);
    if (JSON.stringify(h) !== JSON.stringify(hover)) { hover = h; draw(); }
    showInfo();
  });
  canvas.addEventListener("pointerup", function (e) {
    canvas.classList.remove("dragging");
    if (drag && !drag.moved) {
      var p = local(e);
      selected = pick(p[0], p[1]);
      hover = selected;
      draw();
      showInfo();
    }
    drag = null;
  });
  canvas.addEventListener("pointerleave", function () {
    mouse = null;
    if (hover) { hover = null; draw(); }
    showInfo();
  });
  canvas.addEventListener("contextmenu", function (e) { e.preventDefault(); });
  canvas.addEventListener("wheel", function (e) {
    e.preventDefault();
    var f = Math.exp(Math.max(-1, Math.min(1, e.deltaY * (e.deltaMode === 1 ? 0.05 : 0.0015))));
    cam.dist = Math.max(radius * 0.05, Math.min(radius * 60, cam.dist * f));
    draw();
  }, { passive: false });
  canvas.addEventListener("dblclick", function () { resetCamera(); draw(); });
  document.addEventListener("keydown", function (e) {
    if (e.target && (e.target.tagName === "SELECT" || e.target.tagName === "BUTTON")) return;
    if (e.target === slider && e.key !== " ") return;
    if (e.key === " ") { e.preventDefault(); setPlaying(!playing); }
    else if (e.key === "ArrowRight") { setPlaying(false); setFrame(frame + 1); }
    else if (e.key === "ArrowLeft") { setPlaying(false); setFrame(frame - 1); }
  });

  // ---- legend and summary ----------------------------------------------------------------
  function legend() {
    var el = document.getElementById("legend");
    var stops = RAMP.map(function (s) { return "rgb(" + s[1].join(",") + ") " + (100 * s[0]) + "%"; }).join(", ");
    el.innerHTML = "";
    function div(cls, text) { var d = document.createElement("div"); if (cls) d.className = cls; if (text) d.textContent = text; return d; }
    el.appendChild(div("title", "cable tension (N)"));
    var ramp = div("ramp");
    ramp.style.background = "linear-gradient(to right, " + stops + ")";
    el.appendChild(ramp);
    var ticks = div("ticks");
    ticks.appendChild(div("", "0"));
    ticks.appendChild(div("", fmt(maxTension / 2, 1)));
    ticks.appendChild(div("", fmt(maxTension, 1)));
    el.appendChild(ticks);
    function row(label, paint) {
      var r = div("row"), cv = document.createElement("canvas");
      cv.width = 36; cv.height = 16;
      paint(cv.getContext("2d"));
      r.appendChild(cv);
      r.appendChild(div("", label));
      el.appendChild(r);
    }
    row("slack cable (tension 0)", function (g) {
      g.setLineDash([6, 5]); g.strokeStyle = STYLE.slack; g.lineWidth = 2;
      g.beginPath(); g.moveTo(2, 8); g.lineTo(34, 8); g.stroke();
    });
    row("bar", function (g) {
      g.strokeStyle = STYLE.bar; g.lineWidth = 6; g.lineCap = "round";
      g.beginPath(); g.moveTo(4, 8); g.lineTo(32, 8); g.stroke();
    });
    if (D.pinned.length) row("pinned node", function (g) {
      g.fillStyle = STYLE.pinned;
      g.beginPath(); g.moveTo(18, 2); g.lineTo(12, 13); g.lineTo(24, 13); g.closePath(); g.fill();
      g.fillRect(9, 14, 18, 2);
    });
    if (D.point_masses.length) row("point mass", function (g) {
      g.fillStyle = STYLE.pointMass;
      g.beginPath(); g.arc(18, 8, 6, 0, 2 * Math.PI); g.fill();
    });
    var kinds = { box: "terrain box", heightfield: "terrain heightfield", plane: "terrain plane" };
    Object.keys(kinds).forEach(function (kind) {
      if (!TERRAIN.some(function (t) { return t.kind === kind; })) return;
      row(kinds[kind], function (g) {
        var c = STYLE.terrain[kind];
        g.fillStyle = "rgb(" + c.join(",") + ")"; g.fillRect(2, 3, 32, 10);
        g.strokeStyle = "rgb(" + c.map(function (v) { return Math.round(v * 0.6); }).join(",") + ")";
        g.strokeRect(2.5, 3.5, 31, 9);
      });
    });
    if (D.ground) row("ground plane", function (g) {
      g.fillStyle = STYLE.ground; g.fillRect(2, 3, 32, 10);
      g.strokeStyle = STYLE.groundLine; g.strokeRect(2.5, 3.5, 31, 9);
    });
    if (CONTACTS) {
      var most = CONTACTS.maxForce;
      var what = most > 0
        ? "contact, arrow: " + fmt(most, 1) + " N per " + fmt(most * CONTACTS.perNewton, 3) + " m"
        : "contact: none in this run";
      row(what, function (g) {
        g.strokeStyle = g.fillStyle = STYLE.contact;
        if (most > 0) arrow(g, 6, 8, 34, 8, 2);
        g.beginPath(); g.arc(6, 8, 4, 0, 2 * Math.PI); g.fill();
      });
    }
  }
  document.getElementById("summary").textContent =
    [[N, "node"], [NB, "bar"], [NC, "cable"], [NF, "frame"]]
      .map(([n, what]) => n + " " + what + (n === 1 ? "" : "s"))
      .join(" · ");
  legend();

  // ---- scripted access (tests, console) --------------------------------------------------
  window.viewer = {
    data: D,
    style: STYLE,
    maxTension: maxTension,
    // The contacts drawn at frame k: [{point: [x, y, z], force: [fx, fy, fz]}], or null.
    contacts: function (k) {
      var c = CONTACTS && CONTACTS.frames[k];
      if (!c) return null;
      var out = [];
      for (var m = 0; m < c.points.length; m += 3) {
        out.push({ point: Array.from(c.points.subarray(m, m + 3)), force: Array.from(c.forces.subarray(m, m + 3)) });
      }
      return out;
    },
    frame: function () { return frame; },
    frameCount: NF,
    setFrame: setFrame,
    play: function () { setPlaying(true); },
    pause: function () { setPlaying(false); },
    playing: function () { return playing; },
    // Canvas coordinates (CSS pixels from the canvas's top-left) of a 0-based node, or null.
    project: function (i) { var p = screen[i]; return p ? { x: p[0], y: p[1], depth: p[2] } : null; },
    pick: pick,
    describe: describe,
    camera: cam,
    draw: draw
  };

  window.addEventListener("resize", resize);
  resize();
  setFrame(0);
})();
