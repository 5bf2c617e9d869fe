// The vdbwrap HTML report's 3-D viewer, on three.js (embedded in the page before this script):
// the input and the wrap, coloured plain, by deviation, by part or by defect; the input's
// feature curves; the leak path and its narrowest passage. The scene and the report come from
// the page's JSON script elements; body[data-viewer] ends as "ready" or "error".
(function () {
  'use strict';
  var body = document.body;
  function $(id) { return document.getElementById(id); }
  function fail(text) {
    var m = $('message');
    m.textContent = text;
    m.style.display = 'flex';
    body.setAttribute('data-viewer', 'error');
  }

  var scene, report;
  try {
    scene = JSON.parse($('vdbwrap-scene').textContent);
    report = JSON.parse($('vdbwrap-report').textContent);
  } catch (e) {
    fail('The page data cannot be read: ' + e.message);
    return;
  }
  if (typeof THREE === 'undefined') {
    fail('The viewer library (three.js) did not load; the numbers are on the right.');
    return;
  }

  // ---- data ----
  function bytes(b64) {
    var s = atob(b64 || ''), a = new Uint8Array(s.length);
    for (var i = 0; i < s.length; ++i) a[i] = s.charCodeAt(i);
    return a;
  }
  function floats(b64) { var b = bytes(b64); return new Float32Array(b.buffer, 0, b.length >> 2); }
  function uints(b64) { var b = bytes(b64); return new Uint32Array(b.buffer, 0, b.length >> 2); }
  function ints(b64) { var b = bytes(b64); return new Int32Array(b.buffer, 0, b.length >> 2); }
  function count(n) { return Number(n).toLocaleString('en-US'); }
  function real(v) { return Number(v).toPrecision(4).replace(/\.?0+(e|$)/, '$1'); }
  function el(tag, cls, text) {
    var e = document.createElement(tag);
    if (cls) e.className = cls;
    if (text !== undefined) e.textContent = text;
    return e;
  }

  // ---- colours ----
  var INPUT_COLOUR = [0.72, 0.77, 0.82], WRAP_COLOUR = [0.90, 0.66, 0.38], NEUTRAL = [0.86, 0.86, 0.86];
  var INPUT_DEFECTS = ['hole rim (border edge)', 'non-manifold edge', 'misoriented neighbour', 'degenerate',
                       'self-intersecting'];
  var WRAP_DEFECTS = ['self-intersecting', 'small area', 'sliver', 'short edge', 'long edge', 'normal off the input',
                      'sharp edge lost', 'held back off the input'];
  // One colour per kind across both meshes: self-intersecting is red on either.
  var INPUT_DEFECT_COLOURS = [[0.95, 0.55, 0.05], [0.55, 0.20, 0.75], [0.10, 0.45, 0.90], [0.25, 0.25, 0.25],
                              [0.85, 0.10, 0.10]];
  var WRAP_DEFECT_COLOURS = [[0.85, 0.10, 0.10], [0.95, 0.80, 0.10], [0.90, 0.35, 0.65], [0.10, 0.65, 0.65],
                             [0.15, 0.65, 0.30], [0.45, 0.35, 0.90], [0.60, 0.35, 0.15], [0.55, 0.55, 0.55]];
  function partColour(i) {
    var c = new THREE.Color();
    c.setHSL(((i * 0.618033988749895) % 1 + 1) % 1, 0.55, 0.58);
    return [c.r, c.g, c.b];
  }
  // Cool-warm for signed distances (blue inside, red outside), white to red for unsigned ones.
  function deviationColour(d, max, signed) {
    var t = max > 0 ? Math.max(-1, Math.min(1, d / max)) : 0;
    var mid = [0.93, 0.93, 0.93], lo = [0.23, 0.30, 0.75], hi = [0.71, 0.02, 0.15];
    if (!signed) t = Math.abs(t);
    var end = t < 0 ? lo : hi, a = Math.abs(t);
    return [mid[0] + (end[0] - mid[0]) * a, mid[1] + (end[1] - mid[1]) * a, mid[2] + (end[2] - mid[2]) * a];
  }
  function css(c) { return 'rgb(' + Math.round(255 * c[0]) + ',' + Math.round(255 * c[1]) + ',' + Math.round(255 * c[2]) + ')'; }

  // ---- renderer ----
  var canvas = $('canvas'), renderer;
  try {
    renderer = new THREE.WebGLRenderer({ canvas: canvas, antialias: true });
  } catch (e) {
    fail('WebGL is not available in this browser, so the 3-D view cannot be shown; the numbers are on the right.');
    return;
  }
  renderer.setPixelRatio(window.devicePixelRatio || 1);
  renderer.setClearColor(0xe9edf1, 1);
  var world = new THREE.Scene();
  var camera = new THREE.PerspectiveCamera(35, 1, 0.01, 100);
  camera.up.set(0, 0, 1);
  world.add(camera);
  var sky = new THREE.HemisphereLight(0xffffff, 0x8a96a3, 0.55);
  sky.position.set(0, 0, 1);
  world.add(sky);
  var headlight = new THREE.DirectionalLight(0xffffff, 0.6);
  headlight.position.set(0.3, 0.6, 1);
  camera.add(headlight);
  var VERTEX_COLOURS = THREE.VertexColors !== undefined ? THREE.VertexColors : true;

  function setAttribute(g, name, attr) {
    if (g.setAttribute) g.setAttribute(name, attr); else g.addAttribute(name, attr);
  }

  // Triangles are drawn unshared (three corners each): per-triangle colours (parts, defects)
  // and flat shading need no split vertices.
  function buildMesh(m) {
    var pos = floats(m.positions), tri = uints(m.triangles), n = tri.length / 3;
    var P = new Float32Array(9 * n);
    for (var i = 0; i < 3 * n; ++i) {
      var v = 3 * tri[i];
      P[3 * i] = pos[v];
      P[3 * i + 1] = pos[v + 1];
      P[3 * i + 2] = pos[v + 2];
    }
    var g = new THREE.BufferGeometry();
    setAttribute(g, 'position', new THREE.BufferAttribute(P, 3));
    g.computeVertexNormals();
    var C = new Float32Array(9 * n);
    setAttribute(g, 'color', new THREE.BufferAttribute(C, 3));
    g.computeBoundingSphere();
    var material = new THREE.MeshPhongMaterial({
      vertexColors: VERTEX_COLOURS, side: THREE.DoubleSide, flatShading: true, shininess: 18,
      polygonOffset: true, polygonOffsetFactor: 1, polygonOffsetUnits: 1 });
    var mesh = new THREE.Mesh(g, material);
    world.add(mesh);
    return {
      data: m, mesh: mesh, geometry: g, tri: tri, n: n, colours: C,
      parts: m.parts ? ints(m.parts) : null,
      flags: m.flags ? bytes(m.flags) : null,
      deviation: m.deviation ? floats(m.deviation) : null,
      edges: null
    };
  }

  // A few far points would leave the rest white on a scale to the largest deviation: by
  // default the scale ends at 5 x the 95th percentile, and farther points show its end colour.
  function deviationRange() {
    var dv = scene.deviation;
    return state.fullRange || !(dv.p95_abs > 0) ? dv.max_abs : Math.min(dv.max_abs, 5 * dv.p95_abs);
  }

  function paint(d, mode, plain) {
    var C = d.colours, n = d.n, c, t, k;
    for (t = 0; t < n; ++t) {
      for (k = 0; k < 3; ++k) {
        if (mode === 'deviation' && d.deviation) {
          c = deviationColour(d.deviation[d.tri[3 * t + k]], deviationRange(), scene.deviation.sign !== 'unsigned');
        } else if (mode === 'part' && d.parts) {
          c = partColour(d.parts[t]);
        } else if (mode === 'defect' && d.flags) {
          var f = d.flags[t];
          c = NEUTRAL;
          for (var b = 0; b < d.defectColours.length; ++b) if (f & (1 << b)) { c = d.defectColours[b]; break; }
        } else if (mode === 'defect' || (mode === 'part' && d.data.part_names.length > 1)) {
          c = NEUTRAL;
        } else {
          c = plain;
        }
        C[9 * t + 3 * k] = c[0];
        C[9 * t + 3 * k + 1] = c[1];
        C[9 * t + 3 * k + 2] = c[2];
      }
    }
    d.geometry.attributes.color.needsUpdate = true;
  }

  var input = buildMesh(scene.input);
  input.defectColours = INPUT_DEFECT_COLOURS;
  var wrap = scene.wrap ? buildMesh(scene.wrap) : null;
  if (wrap) wrap.defectColours = WRAP_DEFECT_COLOURS;
  var origin = scene.origin;
  function local(p) { return new THREE.Vector3(p[0] - origin[0], p[1] - origin[1], p[2] - origin[2]); }
  var size = Math.max(scene.diagonal, 1e-12);

  // Feature curves of the input.
  var features = null;
  if (scene.features && scene.features.shown > 0) {
    var fg = new THREE.BufferGeometry();
    setAttribute(fg, 'position', new THREE.BufferAttribute(floats(scene.features.segments), 3));
    features = new THREE.LineSegments(fg, new THREE.LineBasicMaterial({ color: 0x1a2633 }));
    world.add(features);
  }

  // Markers drawn over everything: the leak's path and passage, the largest deviation.
  function marker(at, radius, colour) {
    var s = new THREE.Mesh(new THREE.SphereBufferGeometry(radius, 20, 14),
      new THREE.MeshBasicMaterial({ color: colour, depthTest: false, transparent: true, opacity: 0.85 }));
    s.position.copy(at);
    s.renderOrder = 10;
    return s;
  }
  var leak = report.leak && report.leak.detected ? report.leak : null, leakGroup = null;
  if (leak) {
    leakGroup = new THREE.Group();
    var path = (leak.path || []).map(local);
    if (path.length > 1) {
      var lg = new THREE.BufferGeometry().setFromPoints(path);
      var line = new THREE.Line(lg, new THREE.LineBasicMaterial({ color: 0xd01010, depthTest: false, transparent: true }));
      line.renderOrder = 10;
      leakGroup.add(line);
      leakGroup.add(marker(path[0], size * 0.008, 0x12a040));
    }
    leakGroup.add(marker(local(leak.location), Math.max(leak.width * 0.5, size * 0.006), 0xd01010));
    world.add(leakGroup);
  }
  var maxMarker = null;
  if (scene.deviation && wrap) {
    maxMarker = marker(local(scene.deviation.max_at), size * 0.006, 0x7a0a20);
    world.add(maxMarker);
  }

  // ---- orbit control: drag turns, right/shift-drag pans, the wheel zooms ----
  var target = new THREE.Vector3(), radius = 1, theta = -Math.PI / 3, phi = 1.05, frameRequested = false;
  function render() {
    frameRequested = false;
    var sp = Math.sin(phi);
    camera.position.set(target.x + radius * sp * Math.cos(theta), target.y + radius * sp * Math.sin(theta),
                        target.z + radius * Math.cos(phi));
    camera.near = Math.max(radius * 0.01, 1e-9);
    camera.far = radius + 4 * size;
    camera.updateProjectionMatrix();
    camera.lookAt(target);
    renderer.render(world, camera);
  }
  function redraw() {
    if (!frameRequested) { frameRequested = true; requestAnimationFrame(render); }
  }
  function frame(center, r) {
    target.copy(center);
    radius = r / Math.sin(camera.fov * Math.PI / 360) * 1.08;
    redraw();
  }
  function frameAll() {
    var box = new THREE.Box3();
    [input, wrap].forEach(function (d) { if (d && d.mesh.visible) box.expandByObject(d.mesh); });
    if (box.isEmpty()) box.expandByObject(input.mesh);
    var sphere = box.getBoundingSphere(new THREE.Sphere());
    frame(sphere.center, Math.max(sphere.radius, 1e-9));
  }
  var drag = null;
  canvas.addEventListener('contextmenu', function (e) { e.preventDefault(); });
  canvas.addEventListener('pointerdown', function (e) {
    drag = { x: e.clientX, y: e.clientY, pan: e.button !== 0 || e.shiftKey || e.ctrlKey };
    canvas.setPointerCapture(e.pointerId);
    canvas.style.cursor = 'grabbing';
  });
  canvas.addEventListener('pointermove', function (e) {
    if (!drag) return;
    var dx = e.clientX - drag.x, dy = e.clientY - drag.y;
    drag.x = e.clientX;
    drag.y = e.clientY;
    if (drag.pan) {
      var perPixel = 2 * radius * Math.tan(camera.fov * Math.PI / 360) / Math.max(canvas.clientHeight, 1);
      var right = new THREE.Vector3().setFromMatrixColumn(camera.matrixWorld, 0);
      var up = new THREE.Vector3().setFromMatrixColumn(camera.matrixWorld, 1);
      target.addScaledVector(right, -dx * perPixel).addScaledVector(up, dy * perPixel);
    } else {
      theta -= dx * 0.008;
      phi = Math.max(0.01, Math.min(Math.PI - 0.01, phi - dy * 0.008));
    }
    redraw();
  });
  function endDrag() { drag = null; canvas.style.cursor = 'grab'; }
  canvas.addEventListener('pointerup', endDrag);
  canvas.addEventListener('pointercancel', endDrag);
  canvas.addEventListener('wheel', function (e) {
    e.preventDefault();
    radius *= Math.exp(Math.max(-100, Math.min(100, e.deltaY)) * 0.0015);
    redraw();
  }, { passive: false });
  function resize() {
    var w = Math.max(canvas.clientWidth, 1), h = Math.max(canvas.clientHeight, 1);
    renderer.setSize(w, h, false);
    camera.aspect = w / h;
    redraw();
  }
  if (window.ResizeObserver) new ResizeObserver(resize).observe(canvas); else window.addEventListener('resize', resize);

  // ---- toolbar, legend, note ----
  var state = { show: wrap ? 'wrap' : 'input', colour: wrap && wrap.deviation ? 'deviation' : 'plain', fullRange: false, features: false, leak: !!leak, edges: false };
  var hasParts = scene.input.part_names.length > 1 || (wrap && scene.wrap.part_names.length > 1);
  var toolbar = $('toolbar'), buttons = {};
  function group(label) {
    var g = el('div', 'group');
    g.appendChild(el('span', '', label));
    toolbar.appendChild(g);
    return g;
  }
  function button(g, key, value, text, enabled, title) {
    var b = el('button', '', text);
    b.type = 'button';
    b.disabled = !enabled;
    if (title) b.title = title;
    b.setAttribute('data-' + key, value);
    b.addEventListener('click', function () { state[key] = value; update(); if (key === 'show') frameAll(); });
    g.appendChild(b);
    (buttons[key] = buttons[key] || []).push(b);
  }
  function checkbox(g, key, text, enabled) {
    var l = el('label'), c = el('input');
    c.type = 'checkbox';
    c.checked = state[key];
    c.disabled = !enabled;
    c.id = 'toggle-' + key;
    c.addEventListener('change', function () { state[key] = c.checked; update(); });
    l.appendChild(c);
    l.appendChild(document.createTextNode(' ' + text));
    g.appendChild(l);
  }
  var gShow = group('Show');
  button(gShow, 'show', 'input', 'Input', true);
  button(gShow, 'show', 'wrap', 'Wrap', !!wrap, wrap ? '' : 'There is no wrap: the run stopped');
  button(gShow, 'show', 'both', 'Both', !!wrap);
  var gColour = group('Colour');
  button(gColour, 'colour', 'plain', 'Plain', true);
  button(gColour, 'colour', 'deviation', 'Deviation', !!(wrap && wrap.deviation),
         wrap && wrap.deviation ? 'Distance of the wrap to the input' : 'No deviation field in this report');
  button(gColour, 'colour', 'part', 'Part', hasParts, hasParts ? '' : 'The input has one part');
  button(gColour, 'colour', 'defect', 'Defect', true);
  var gMore = group('');
  checkbox(gMore, 'features', 'Feature curves', !!features);
  checkbox(gMore, 'edges', 'Edges', true);
  if (leak) checkbox(gMore, 'leak', 'Leak path', true);
  var gGo = group('');
  var reset = el('button', '', 'Reset view');
  reset.type = 'button';
  reset.addEventListener('click', frameAll);
  gGo.appendChild(reset);
  function goButton(text, at) {
    var b = el('button', '', text);
    b.type = 'button';
    b.addEventListener('click', function () { frame(local(at), size * 0.06); });
    gGo.appendChild(b);
  }
  if (leak) goButton('Go to the passage', leak.location);
  if (maxMarker) goButton('Go to the largest deviation', scene.deviation.max_at);

  function setEdges(d, on) {
    if (on && !d.edges) {
      d.edges = new THREE.Mesh(d.geometry, new THREE.MeshBasicMaterial({
        color: 0x26323e, wireframe: true, transparent: true, opacity: 0.35, depthWrite: false }));
      world.add(d.edges);
    }
    if (d.edges) d.edges.visible = on && d.mesh.visible;
  }

  function legend() {
    var L = $('legend');
    L.innerHTML = '';
    var shown = [];
    if (state.show !== 'wrap') shown.push(['Input', input, INPUT_DEFECTS, INPUT_COLOUR]);
    if (wrap && state.show !== 'input') shown.push(['Wrap', wrap, WRAP_DEFECTS, WRAP_COLOUR]);
    function entry(colour, text) {
      var e = el('div', 'entry'), s = el('span', 'swatch');
      s.style.background = css(colour);
      e.appendChild(s);
      e.appendChild(el('span', '', text));
      L.appendChild(e);
    }
    if (state.colour === 'deviation' && scene.deviation) {
      var dv = scene.deviation, signed = dv.sign !== 'unsigned';
      L.appendChild(el('div', 'title', signed ? 'Distance of the wrap to the input (' +
        (dv.sign === 'outside' ? '+ outside, - inside' : '+ in front of its triangles') + ')' : 'Distance of the wrap to the input'));
      var range = deviationRange(), clipped = range < dv.max_abs;
      var stops = [];
      for (var i = 0; i <= 10; ++i) {
        var x = signed ? -1 + i / 5 : i / 10;
        stops.push(css(deviationColour(x * range, range, signed)) + ' ' + (i * 10) + '%');
      }
      var bar = el('div', 'bar');
      bar.style.background = 'linear-gradient(to right,' + stops.join(',') + ')';
      L.appendChild(bar);
      var ticks = el('div', 'ticks');
      var pct = function (v) { return dv.diagonal > 0 ? ' (' + real(100 * v / dv.diagonal) + ' % of the diagonal)' : ''; };
      ticks.appendChild(el('span', '', signed ? (clipped ? '\u2264 ' : '') + '\u2212' + real(range) : '0'));
      if (signed) ticks.appendChild(el('span', '', '0'));
      ticks.appendChild(el('span', '', (clipped ? '\u2265 ' : '') + '+' + real(range)));
      L.appendChild(ticks);
      L.appendChild(el('div', '', 'scale \u00b1' + real(range) + pct(range) +
                       (clipped ? ', 5 \u00d7 the 95th percentile' : '')));
      var full = el('label'), box = el('input');
      box.type = 'checkbox';
      box.id = 'toggle-full-range';
      box.checked = state.fullRange;
      box.addEventListener('change', function () { state.fullRange = box.checked; update(); });
      full.appendChild(box);
      full.appendChild(document.createTextNode(' scale to the largest deviation'));
      L.appendChild(full);
      var stats = el('div', '', '|distance|: mean ' + real(dv.mean_abs) + ', 95th percentile ' + real(dv.p95_abs) +
                     ', max ' + real(dv.max_abs) + pct(dv.max_abs));
      stats.setAttribute('data-deviation-max', dv.max_abs);
      L.appendChild(stats);
    } else if (state.colour === 'part') {
      var names = scene.input.part_names.length > 1 ? scene.input.part_names : scene.wrap.part_names;
      L.appendChild(el('div', 'title', 'Parts'));
      for (var p = 0; p < names.length && p < 24; ++p) entry(partColour(p), names[p] || 'part ' + p);
      if (names.length > 24) L.appendChild(el('div', '', '... ' + (names.length - 24) + ' more'));
    } else if (state.colour === 'defect') {
      shown.forEach(function (s) {
        var d = s[1];
        L.appendChild(el('div', 'title', s[0] + ' defects (triangles)'));
        if (!d.flags) { L.appendChild(el('div', '', 'no per-triangle defect data in this report')); return; }
        var counts = d.data.flag_counts, any = false;
        for (var b = 0; b < s[2].length; ++b) {
          if (!counts[b]) continue;
          any = true;
          entry(d.defectColours[b], s[2][b] + ': ' + count(counts[b]));
        }
        if (d === input && !d.data.intersections_searched) L.appendChild(el('div', '', 'self-intersections not searched (input too big)'));
        if (!any) entry(NEUTRAL, 'none');
      });
    } else {
      shown.forEach(function (s) { entry(s[3], s[0]); });
    }
    if (leak && state.leak) {
      L.appendChild(el('div', 'title', 'Leak'));
      entry([0.82, 0.06, 0.06], 'path and narrowest passage (' + real(leak.width) + ' wide)');
      if (leak.path && leak.path.length > 1) entry([0.07, 0.63, 0.25], 'seed point');
    }
  }

  function note() {
    var parts = [];
    [['input', scene.input], ['wrap', scene.wrap]].forEach(function (e) {
      var m = e[1];
      if (m && m.clustered)
        parts.push('the ' + e[0] + "'s " + count(m.triangles_total) + ' triangles are shown as ' + count(m.triangles_shown) +
                   ' (vertex clustering, cell ' + real(m.cluster_size) + ')');
    });
    var text = parts.length ? 'Display only: ' + parts.join('; ') + '. The numbers are those of the full meshes. ' : '';
    if (features) text += 'Feature curves: ' + count(scene.features.total) + ' sharp edges (over ' +
      real(scene.features.angle_deg) + ' degrees)' + (scene.features.shown < scene.features.total ? ', ' +
      count(scene.features.shown) + ' drawn' : '') + '. ';
    text += 'Drag to turn, right-drag or shift-drag to pan, wheel to zoom.';
    var n = $('note');
    n.textContent = text;
    n.setAttribute('data-clustered', parts.length ? 'true' : 'false');
  }

  function update() {
    input.mesh.visible = state.show !== 'wrap';
    if (wrap) {
      wrap.mesh.visible = state.show !== 'input';
      // Both: the wrap see-through over the input.
      var both = state.show === 'both';
      wrap.mesh.material.transparent = both;
      wrap.mesh.material.opacity = both ? 0.45 : 1;
      wrap.mesh.material.depthWrite = !both;
      wrap.mesh.material.needsUpdate = true;
      paint(wrap, state.colour, WRAP_COLOUR);
      setEdges(wrap, state.edges);
    }
    paint(input, state.colour === 'deviation' ? 'plain' : state.colour, INPUT_COLOUR);
    setEdges(input, state.edges);
    if (features) features.visible = state.features;
    if (leakGroup) leakGroup.visible = state.leak;
    if (maxMarker) maxMarker.visible = state.colour === 'deviation' && wrap.mesh.visible;
    Object.keys(buttons).forEach(function (key) {
      buttons[key].forEach(function (b) { b.classList.toggle('on', b.getAttribute('data-' + key) === state[key]); });
    });
    legend();
    redraw();
  }

  try {
    note();
    update();
    resize();
    frameAll();
    render();
    body.setAttribute('data-viewer', 'ready');
  } catch (e) {
    fail('The 3-D view failed: ' + e.message);
    throw e;
  }
})();
