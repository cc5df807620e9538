/* urdf2links motion player (urdf2links/view/animation.py writes the page around it).
 *
 * Drives meshcat's viewer (MeshCat.Viewer; three.js r132 as MeshCat.THREE, both from the meshcat
 * Python package, inlined in the page) from the poses embedded in the page: no network, no server.
 * Each element of class "u2l-motion" holds its data (<script type="application/json"
 * class="u2l-data">), a viewer pane, controls and side panels (SVG plots with a cursor line).
 *
 * Data: t (F,) frame times; links (L,) node names; shapes [{link, kind, origin (16, column-major),
 * color, source, ... box size, cylinder radius/length (axis z), sphere radius, mesh vertices
 * (base64 float32) and faces (base64 uint16/uint32); runs: the runs that draw it, when runs show
 * different robots (two descriptions of one robot)}]; runs [{name, path, label, ghost, poses:
 * base64 float32 (F, L, 7) = position, quaternion (x, y, z, w)}]; base: {poses (F, 7), plate
 * [sx, sy, cx, cy]} or null; camera {target, offset} (world, z up); readout [{label, unit,
 * log, values (F,)}]; frame_size (m).
 *
 * URL parameters (after # or ?): t=SECONDS shows that time, paused; play=1 plays from there; speed=X.
 * When ready the element gets data-ready="1" and data-top (its top in the page, CSS pixels).
 */
(function () {
  "use strict";

  function b64(s, Type) {
    const bin = atob(s);
    const bytes = new Uint8Array(bin.length);
    for (let i = 0; i < bin.length; i++) bytes[i] = bin.charCodeAt(i);
    return new Type(bytes.buffer);
  }

  function urlParams() {
    const out = {};
    const text = (location.hash || "").replace(/^#/, "") + "&" + (location.search || "").replace(/^\?/, "");
    text.split("&").forEach(function (kv) {
      if (!kv) return;
      const parts = kv.split("=");
      out[decodeURIComponent(parts[0])] = parts.length > 1 ? decodeURIComponent(parts[1]) : "";
    });
    return out;
  }

  function geometry(THREE, s) {
    if (s.kind === "mesh") {
      const g = new THREE.BufferGeometry();
      g.setAttribute("position", new THREE.BufferAttribute(b64(s.vertices, Float32Array), 3));
      g.setIndex(new THREE.BufferAttribute(b64(s.faces, s.index === "u16" ? Uint16Array : Uint32Array), 1));
      const flat = g.toNonIndexed();  // one normal per triangle: decimated CAD meshes keep their edges
      flat.computeVertexNormals();
      return flat;
    }
    if (s.kind === "box") return new THREE.BoxGeometry(s.size[0], s.size[1], s.size[2]);
    if (s.kind === "cylinder") {
      const g = new THREE.CylinderGeometry(s.radius, s.radius, s.length, 32);
      g.rotateX(Math.PI / 2);  // three.js cylinders run along y, URDF cylinders along z
      return g;
    }
    if (s.kind === "sphere") return new THREE.SphereGeometry(s.radius, 32, 16);
    return null;  // a frame: axes, built per run
  }

  function material(THREE, s, run) {
    if (run.ghost) {
      // pushed back in depth: where it coincides with the solid robot the robot hides it, and it
      // shows where the two runs part
      return new THREE.MeshPhongMaterial({color: 0xff7a00, transparent: true, opacity: 0.35, depthWrite: false,
                                          polygonOffset: true, polygonOffsetFactor: 2, polygonOffsetUnits: 8});
    }
    const color = s.color ? new THREE.Color(s.color[0], s.color[1], s.color[2])
                          : new THREE.Color(s.source === "collision" ? 0x6f8fb8 : 0xb4bac4);
    return new THREE.MeshPhongMaterial({color: color, shininess: 40});
  }

  function frameObject(THREE, size, ghost) {
    const axes = new THREE.AxesHelper(size);
    if (ghost) {
      axes.material.transparent = true;
      axes.material.opacity = 0.35;
      axes.material.depthWrite = false;
    }
    return axes;
  }

  function place(THREE, obj, origin) {
    const m = new THREE.Matrix4().fromArray(origin);
    m.decompose(obj.position, obj.quaternion, obj.scale);
    return obj;
  }

  function setPose(node, P, i, j, a) {
    // position: linear; rotation: normalized linear interpolation of the quaternions (same hemisphere)
    const b = 1 - a;
    node.position.set(b * P[i] + a * P[j], b * P[i + 1] + a * P[j + 1], b * P[i + 2] + a * P[j + 2]);
    const dot = P[i + 3] * P[j + 3] + P[i + 4] * P[j + 4] + P[i + 5] * P[j + 5] + P[i + 6] * P[j + 6];
    const s = dot < 0 ? -a : a;
    node.quaternion.set(b * P[i + 3] + s * P[j + 3], b * P[i + 4] + s * P[j + 4],
                        b * P[i + 5] + s * P[j + 5], b * P[i + 6] + s * P[j + 6]).normalize();
  }

  function setup(root) {
    const data = JSON.parse(root.querySelector("script.u2l-data").textContent);
    const pane = root.querySelector(".u2l-viewer");
    const status = root.querySelector(".u2l-status");
    if (typeof MeshCat === "undefined") {
      status.textContent = "The viewer script did not load; the 3D view is unavailable.";
      return;
    }
    const THREE = MeshCat.THREE;
    let viewer;
    try {
      viewer = new MeshCat.Viewer(pane);
    } catch (err) {
      status.textContent = "This browser cannot show the 3D view (WebGL unavailable: " + err + ").";
      return;
    }
    const resize = viewer.set_3d_pane_size.bind(viewer);  // meshcat sizes to the window's height
    viewer.set_3d_pane_size = function (w, h) {
      resize(w === undefined ? pane.clientWidth : w, h === undefined ? pane.clientHeight : h);
    };
    viewer.set_3d_pane_size();
    viewer.set_property(["Background"], "top_color", [0.88, 0.91, 0.95]);
    viewer.set_property(["Background"], "bottom_color", [0.52, 0.58, 0.67]);
    viewer.set_property(["Axes"], "visible", false);

    const T = data.t, F = T.length, L = data.links.length;
    const geoms = data.shapes.map(function (s) { return geometry(THREE, s); });
    const runs = data.runs.map(function (run, r) {
      const nodes = data.links.map(function (link) { return viewer.scene_tree.find([run.path, link]).object; });
      data.shapes.forEach(function (s, k) {
        if (s.runs && s.runs.indexOf(r) < 0) return;  // another description's shape: not this run's robot
        const obj = s.kind === "frame" ? frameObject(THREE, data.frame_size, run.ghost)
                                       : new THREE.Mesh(geoms[k], material(THREE, s, run));
        if (run.ghost) obj.renderOrder = 1;  // translucent: drawn after the solid robot
        viewer.set_object([run.path, data.links[s.link], "shape" + k], place(THREE, obj, s.origin));
      });
      return {nodes: nodes, poses: b64(run.poses, Float32Array), path: run.path, visible: true};
    });
    let base = null;
    if (data.base) {
      const p = data.base.plate;
      const plate = new THREE.Mesh(new THREE.BoxGeometry(p[0], p[1], data.frame_size * 0.15),
        new THREE.MeshPhongMaterial({color: 0x3d5a80, transparent: true, opacity: 0.35, depthWrite: false}));
      plate.position.set(p[2], p[3], -data.frame_size * 0.08);
      viewer.set_object(["base_A", "deck"], plate);
      viewer.set_object(["base_A", "axes"], frameObject(THREE, 2 * data.frame_size, false));
      base = {node: viewer.scene_tree.find(["base_A"]).object, poses: b64(data.base.poses, Float32Array)};
    }

    // camera: orbit about the motion's centre, from the offset. The camera's parent is meshcat's
    // y-up "rotated" frame, which coincides with three.js's world: world (x, y, z), z up, is
    // (x, z, -y) there; the orbit target is in the same frame.
    const c = data.camera;
    const yUp = function (v) { return [v[0], v[2], -v[1]]; };
    const tg = yUp(c.target), off = yUp(c.offset);
    viewer.controls.target.set(tg[0], tg[1], tg[2]);
    viewer.camera.position.set(tg[0] + off[0], tg[1] + off[1], tg[2] + off[2]);
    viewer.controls.update();
    const dist = Math.hypot(c.offset[0], c.offset[1], c.offset[2]);
    viewer.camera.near = dist / 200;
    viewer.camera.far = dist * 50;

    const slider = root.querySelector(".u2l-slider");
    const timeText = root.querySelector(".u2l-time");
    const playButton = root.querySelector(".u2l-play");
    const speedSelect = root.querySelector(".u2l-speed");
    const readout = root.querySelector(".u2l-readout");
    const cursors = Array.from(root.querySelectorAll("svg.u2l-panel")).map(function (svg) {
      const d = svg.dataset;
      return {line: svg.querySelector(".u2l-cursor"), t0: +d.t0, t1: +d.t1, x0: +d.x0, x1: +d.x1};
    });
    const tEnd = T[F - 1];
    let time = 0, playing = false, last = null, speed = 1;

    function frameAt(t) {  // last frame at or before t, and the fraction to the next
      let lo = 0, hi = F - 1;
      if (t >= T[hi]) return [hi, hi, 0];
      while (hi - lo > 1) {
        const mid = (lo + hi) >> 1;
        if (T[mid] <= t) lo = mid; else hi = mid;
      }
      const a = T[hi] > T[lo] ? Math.min(1, Math.max(0, (t - T[lo]) / (T[hi] - T[lo]))) : 0;
      return [lo, hi, a];
    }

    function show(t) {
      time = Math.min(Math.max(t, 0), tEnd);
      const [k, k1, a] = frameAt(time);
      runs.forEach(function (run) {
        if (!run.visible) return;
        for (let l = 0; l < L; l++) setPose(run.nodes[l], run.poses, (k * L + l) * 7, (k1 * L + l) * 7, a);
      });
      if (base) setPose(base.node, base.poses, k * 7, k1 * 7, a);
      viewer.set_dirty();
      slider.value = time;
      timeText.textContent = "t = " + time.toFixed(3) + " s / " + tEnd.toFixed(3) + " s";
      cursors.forEach(function (cur) {
        const x = cur.x0 + (time - cur.t0) / ((cur.t1 - cur.t0) || 1) * (cur.x1 - cur.x0);
        cur.line.setAttribute("x1", x.toFixed(1));
        cur.line.setAttribute("x2", x.toFixed(1));
      });
      const kk = a > 0.5 ? k1 : k;
      readout.textContent = data.readout.map(function (r) {
        const v = Number(r.values[kk]);
        return r.label + " = " + (r.log ? v.toExponential(2) : v.toPrecision(4)) + (r.unit ? " " + r.unit : "");
      }).join("   ");
    }

    function tick(now) {
      if (!playing) return;
      if (last !== null) {
        time += (now - last) / 1000 * speed;
        if (time > tEnd) time = 0;  // loop
      }
      last = now;
      show(time);
      requestAnimationFrame(tick);
    }

    function play(on) {
      playing = on;
      last = null;
      playButton.textContent = on ? "Pause" : "Play";
      if (on) requestAnimationFrame(tick);
    }

    playButton.addEventListener("click", function () { play(!playing); });
    slider.addEventListener("input", function () { play(false); show(+slider.value); });
    speedSelect.addEventListener("change", function () { speed = +speedSelect.value; });
    root.querySelectorAll("input.u2l-run").forEach(function (box) {
      box.addEventListener("change", function () {
        const run = runs.find(function (r) { return r.path === box.value; });
        run.visible = box.checked;
        viewer.set_property([run.path], "visible", box.checked);
        show(time);
      });
    });

    const params = urlParams();
    if (params.speed) {
      speed = +params.speed || 1;
      speedSelect.value = String(speed);
    }
    status.textContent = "";
    root.dataset.ready = "1";
    root.dataset.top = String(Math.round(root.getBoundingClientRect().top + window.scrollY));  // for screenshots
    if (params.t !== undefined) {
      show(+params.t || 0);
      play(params.play === "1");
    } else {
      show(0);
      play(true);
    }
  }

  document.querySelectorAll(".u2l-motion").forEach(setup);
})();
