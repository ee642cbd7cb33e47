// viewer.js - plays a sem animation in the browser (the page `sem view` writes).
//
// The page carries everything it needs: three.js (r111's global-script build, as Debian's
// libjs-three ships it), the animation as a base64 glb (animation.glb of `sem run`: one
// mesh per object, one primitive per part, the frames as morph targets driven by one
// animation) and summary.json's per-frame energies. Nothing is fetched, so the page works
// from file:// and without a network.
//
// window.semViewer is the page's state for scripts and tests: ready (the animation is
// loaded and drawn), frameCount, frame, setFrame(k), play(), pause(), errors.
(function () {
  'use strict';

  var viewer = { ready: false, frameCount: 0, frame: 0, errors: [] };
  window.semViewer = viewer;
  window.addEventListener('error', function (e) { viewer.errors.push(String(e.message || e)); });

  var PALETTE = ['#4e79a7', '#f28e2b', '#e15759', '#76b7b2', '#59a14f', '#edc948', '#b07aa1', '#ff9da7'];

  function fail(message) {
    viewer.errors.push(message);
    document.getElementById('message').textContent = message;
    console.error(message);
  }

  function decodeBase64(text) {
    var binary = atob(text.replace(/\s+/g, ''));
    var bytes = new Uint8Array(binary.length);
    for (var i = 0; i < binary.length; ++i) bytes[i] = binary.charCodeAt(i);
    return bytes.buffer;
  }

  var summary = null;
  try {
    summary = JSON.parse(document.getElementById('sem-summary').textContent);
  } catch (e) {
    summary = null;
  }

  if (typeof THREE === 'undefined' || !THREE.GLTFLoader || !THREE.OrbitControls) {
    fail('three.js did not load');
    return;
  }

  // ---- renderer, scene, lights ----
  var view = document.getElementById('view');
  var renderer = new THREE.WebGLRenderer({ antialias: true, preserveDrawingBuffer: true });
  renderer.setPixelRatio(window.devicePixelRatio || 1);
  if ('outputEncoding' in renderer && THREE.sRGBEncoding !== undefined) renderer.outputEncoding = THREE.sRGBEncoding;
  else renderer.gammaOutput = true;
  renderer.shadowMap.enabled = true;
  renderer.shadowMap.type = THREE.PCFSoftShadowMap;
  view.appendChild(renderer.domElement);

  var scene = new THREE.Scene();
  scene.background = new THREE.Color(0xe9ebef);
  scene.add(new THREE.HemisphereLight(0xdfe8f5, 0x8a8275, 0.65));
  var sun = new THREE.DirectionalLight(0xffffff, 0.75);
  sun.castShadow = true;
  sun.shadow.mapSize.set(2048, 2048);
  sun.shadow.bias = -0.0005;
  scene.add(sun);
  scene.add(sun.target);
  var camera = new THREE.PerspectiveCamera(30, 1, 0.01, 1000);
  var controls = new THREE.OrbitControls(camera, renderer.domElement);

  var mixer = null, action = null, times = [0], playing = true, clock = new THREE.Clock();

  function resize() {
    var w = Math.max(1, view.clientWidth), h = Math.max(1, view.clientHeight);
    renderer.setSize(w, h, false);
    camera.aspect = w / h;
    camera.updateProjectionMatrix();
    drawPlot();
  }

  function draw() {
    controls.update();
    renderer.render(scene, camera);
  }

  // Box of the whole animation: every frame is base + one morph target (positions are
  // relative), so each shared position attribute is scanned once per target.
  function animationBox(root) {
    root.updateMatrixWorld(true);
    var box = new THREE.Box3(), seen = [], p = new THREE.Vector3();
    root.traverse(function (object) {
      if (!object.isMesh) return;
      var geometry = object.geometry, base = geometry.attributes.position;
      var local = new THREE.Box3();
      for (var k = 0; k < seen.length; ++k)
        if (seen[k].attribute === base) local = seen[k].box;
      if (local.isEmpty()) {
        var targets = (geometry.morphAttributes && geometry.morphAttributes.position) || [];
        var a = base.array;
        for (var v = 0; v < base.count; ++v) local.expandByPoint(p.set(a[3 * v], a[3 * v + 1], a[3 * v + 2]));
        for (var t = 0; t < targets.length; ++t) {
          var d = targets[t].array;
          for (var u = 0; u < base.count; ++u)
            local.expandByPoint(p.set(a[3 * u] + d[3 * u], a[3 * u + 1] + d[3 * u + 1], a[3 * u + 2] + d[3 * u + 2]));
        }
        seen.push({ attribute: base, box: local });
      }
      box.union(local.clone().applyMatrix4(object.matrixWorld));
    });
    return box;
  }

  function frameAt(time) {
    var k = 0;
    while (k + 1 < times.length && times[k + 1] <= time + 1e-9) ++k;
    return k;
  }

  function showFrame(k) {
    viewer.frame = k;
    document.getElementById('frame').value = String(k);
    var t = times[k] || 0;
    document.getElementById('time').textContent =
      'frame ' + k + ' / ' + (times.length - 1) + ',  t = ' + t.toFixed(3) + ' s';
    drawPlot();
  }

  viewer.setFrame = function (k) {
    k = Math.max(0, Math.min(times.length - 1, Math.round(k)));
    viewer.pause();
    if (action) {
      action.time = times[k];
      mixer.update(0);
    }
    showFrame(k);
    draw();
  };
  viewer.play = function () {
    playing = mixer !== null;
    clock.getDelta();
    document.getElementById('play').textContent = playing ? 'Pause' : 'Play';
  };
  viewer.pause = function () {
    playing = false;
    document.getElementById('play').textContent = 'Play';
  };

  document.getElementById('play').addEventListener('click', function () {
    if (playing) viewer.pause(); else viewer.play();
  });
  document.getElementById('frame').addEventListener('input', function (e) {
    viewer.setFrame(Number(e.target.value));
  });
  window.addEventListener('keydown', function (e) {
    if (e.key === ' ') {
      e.preventDefault();
      if (playing) viewer.pause(); else viewer.play();
    } else if (e.key === 'ArrowRight') viewer.setFrame(viewer.frame + 1);
    else if (e.key === 'ArrowLeft') viewer.setFrame(viewer.frame - 1);
  });
  window.addEventListener('resize', resize);

  // ---- energies under the view ----
  function series() {
    var frames = summary && summary.frames;
    if (!frames || !frames.length) return null;
    function column(key, relative) {
      var v0 = relative ? (frames[0][key] || 0) : 0;
      return frames.map(function (f) { return (f[key] || 0) - v0; });
    }
    var total = frames.map(function (f) {
      return (f.kinetic_energy || 0) + (f.elastic_energy || 0) + (f.gravity_energy || 0) + (f.error_energy || 0);
    });
    var total0 = total[0];
    return {
      time: frames.map(function (f) { return f.time || 0; }),
      lines: [
        { name: 'kinetic', values: column('kinetic_energy', false) },
        { name: 'elastic', values: column('elastic_energy', false) },
        { name: 'gravity (from frame 0)', values: column('gravity_energy', true) },
        { name: 'error', values: column('error_energy', false) },
        { name: 'total (from frame 0)', values: total.map(function (v) { return v - total0; }) }
      ]
    };
  }
  var plotData = series();

  function drawPlot() {
    var canvas = document.getElementById('energy');
    var ratio = window.devicePixelRatio || 1;
    var w = canvas.clientWidth, h = canvas.clientHeight;
    canvas.width = Math.max(1, Math.round(w * ratio));
    canvas.height = Math.max(1, Math.round(h * ratio));
    var g = canvas.getContext('2d');
    g.setTransform(ratio, 0, 0, ratio, 0, 0);
    g.clearRect(0, 0, w, h);
    g.font = '12px system-ui, sans-serif';
    g.fillStyle = '#333';
    if (!plotData) {
      g.fillText('no energies (summary.json was not found next to animation.glb)', 10, 20);
      return;
    }
    var left = 70, right = w - 10, top = 22, bottom = h - 22;
    var t0 = plotData.time[0], t1 = plotData.time[plotData.time.length - 1];
    if (!(t1 > t0)) t1 = t0 + 1;
    var lo = 0, hi = 0;
    plotData.lines.forEach(function (l) {
      l.values.forEach(function (v) { if (isFinite(v)) { lo = Math.min(lo, v); hi = Math.max(hi, v); } });
    });
    if (!(hi > lo)) hi = lo + 1;
    function X(t) { return left + (right - left) * (t - t0) / (t1 - t0); }
    function Y(v) { return bottom - (bottom - top) * (v - lo) / (hi - lo); }
    g.strokeStyle = '#ccc';
    g.lineWidth = 1;
    g.beginPath();
    g.moveTo(left, Y(0)); g.lineTo(right, Y(0));
    g.moveTo(left, top); g.lineTo(left, bottom); g.lineTo(right, bottom);
    g.stroke();
    g.fillStyle = '#555';
    g.textAlign = 'right';
    g.fillText(hi.toPrecision(3) + ' J', left - 6, top + 4);
    g.fillText(lo.toPrecision(3) + ' J', left - 6, bottom + 4);
    g.textAlign = 'center';
    g.fillText(t0.toFixed(2) + ' s', left, h - 6);
    g.fillText(t1.toFixed(2) + ' s', right - 20, h - 6);
    g.textAlign = 'left';
    var x = left + 10;
    plotData.lines.forEach(function (l, i) {
      g.strokeStyle = PALETTE[i % PALETTE.length];
      g.lineWidth = 1.5;
      g.beginPath();
      l.values.forEach(function (v, k) {
        var px = X(plotData.time[k]), py = Y(v);
        if (k === 0) g.moveTo(px, py); else g.lineTo(px, py);
      });
      g.stroke();
      g.fillStyle = PALETTE[i % PALETTE.length];
      g.fillRect(x, 8, 10, 3);
      g.fillStyle = '#333';
      g.fillText(l.name, x + 14, 13);
      x += g.measureText(l.name).width + 30;
    });
    var now = times[viewer.frame] || 0;
    g.strokeStyle = '#222';
    g.beginPath();
    g.moveTo(X(now), top);
    g.lineTo(X(now), bottom);
    g.stroke();
  }

  // ---- the animation ----
  if (summary) {
    var parts = [];
    if (summary.frames) parts.push(summary.frames.length + ' frames');
    if (summary.dofs) parts.push(summary.dofs + ' degrees of freedom');
    if (summary.status && summary.status !== 'ok') parts.push('run ' + summary.status + ': ' + (summary.error || ''));
    document.getElementById('info').textContent = parts.join(', ');
  }

  var glb;
  try {
    glb = decodeBase64(document.getElementById('sem-glb').textContent);
  } catch (e) {
    fail('the animation in this page is damaged: ' + e);
    return;
  }
  new THREE.GLTFLoader().parse(glb, '', function (gltf) {
    var root = gltf.scene;
    root.traverse(function (object) {
      if (object.isMesh) {
        object.castShadow = true;
        object.receiveShadow = true;
      }
    });
    scene.add(root);
    var box = animationBox(root);
    var center = box.getCenter(new THREE.Vector3()), size = box.getSize(new THREE.Vector3());
    var radius = Math.max(0.5 * size.length(), 1e-6);
    // the ground under the lowest point of the whole animation
    var ground = new THREE.Mesh(new THREE.PlaneBufferGeometry(40 * radius, 40 * radius),
                                new THREE.MeshLambertMaterial({ color: 0xc4c4c0 }));
    ground.rotation.x = -Math.PI / 2;
    ground.position.set(center.x, box.min.y - 1e-3 * radius, center.z);
    ground.receiveShadow = true;
    scene.add(ground);
    // the camera of `sem render` (azimuth -60, elevation 25 degrees; z up in sem is y up here)
    var az = -60 * Math.PI / 180, el = 25 * Math.PI / 180;
    var towards = new THREE.Vector3(Math.cos(el) * Math.cos(az), Math.sin(el), -Math.cos(el) * Math.sin(az));
    var distance = 1.15 * radius / Math.sin(0.5 * camera.fov * Math.PI / 180);
    camera.position.copy(center).addScaledVector(towards, distance);
    camera.near = distance / 100;
    camera.far = distance * 100;
    controls.target.copy(center);
    var lightAz = az + 35 * Math.PI / 180, lightEl = 55 * Math.PI / 180;
    sun.position.copy(center).addScaledVector(new THREE.Vector3(Math.cos(lightEl) * Math.cos(lightAz), Math.sin(lightEl),
                                                                -Math.cos(lightEl) * Math.sin(lightAz)), 3 * radius);
    sun.target.position.copy(center);
    var s = sun.shadow.camera;
    s.left = s.bottom = -2 * radius;
    s.right = s.top = 2 * radius;
    s.near = 0.01 * radius;
    s.far = 8 * radius;
    s.updateProjectionMatrix();

    if (gltf.animations && gltf.animations.length) {
      mixer = new THREE.AnimationMixer(root);
      var clip = gltf.animations[0];
      action = mixer.clipAction(clip);
      action.play();
      times = Array.prototype.slice.call(clip.tracks[0].times);
    }
    viewer.frameCount = times.length;
    document.getElementById('frame').max = String(times.length - 1);
    resize();
    viewer.play();
    showFrame(0);
    draw();
    viewer.ready = true;
    (function loop() {
      requestAnimationFrame(loop);
      if (playing && mixer) {
        mixer.update(clock.getDelta());
        var k = frameAt(action.time);
        if (k !== viewer.frame) showFrame(k);
      }
      draw();
    })();
  }, function (error) {
    fail('cannot read the animation: ' + (error && error.message ? error.message : error));
  });
  resize();
})();
