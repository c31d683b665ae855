#!/usr/bin/env python3
"""Tests of appell view and appell export (docs/viewer.md "Verification").

    test_viewer.py APPELL SCENES_DIR WORK_DIR CHECK

CHECK is one of:
  pages    every example scene: `appell run` (short, with the coordinates, poses and contacts
           channels), `appell view --run`, the page loaded in headless Chromium with no console
           error or warning; at four frames the page's world matrix of every body (three.js
           matrixWorld, doubles) equals the CSV's poses channel (BODY.pos.*, BODY.rot.*, written
           by the run from its own state) to 1e-9, and each drawn contact trace ends at the
           CSV's contact point of that row (float32: the trace is a GPU vertex buffer)
  pixels   the rolling disk: screenshots at two frames differ at the disk's projected image
           centre of the first frame (the disk moved away) and match at a ground point far from
           the disk's path (nothing moved there)
  events   a page with a hand-written run record (status and two events) shows each event on
           the timeline at its time, and the status
  errors   bad input to appell view and export: a CSV without the coordinates, an unknown
           --plot column, a malformed row, another --format: exit 2, one message naming the
           column, row or option, and no output file
  gltf     the bicycle's glTF export passes the Khronos validator (no errors) and its animation
           samples equal the CSV's poses to float32 rounding
  terrain  the tilted plane (ball_incline) and the bowl (ball_bowl): the page draws the ground
           the scene defines (the plane's world matrix has the scene's normal as its z axis and
           the ball's centre is its radius above the drawn plane; the sphere is drawn at the
           scene's centre and radius, from inside, and the ball's centre is R - r from the drawn
           centre), to 1e-9 in every frame; a pixel of the drawn ground differs from the
           background; the glTF export has a ground mesh on the same surface (float32) and
           passes the validator; the height field (ball_bumps) is drawn as a mesh whose
           vertices lie on h(x, y) (float32), none inside the ball, one within the grid
           spacing of its centre's distance r

Exit 0 pass, 1 fail, 77 skip (only when chromium or node is not installed at all).
"""
import json
import math
import os
import shutil
import struct
import subprocess
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import cdp  # noqa: E402

HERE = os.path.dirname(os.path.abspath(__file__))
SCENES = ["rolling_disk", "skate_incline", "chaplygin_sleigh", "turntable_ball", "hoffmann",
          "rattleback", "heavy_top", "diff_drive", "diff_drive_caster", "diff_drive_loops",
          "car_ackermann", "sleigh_wheel", "skate_wheel", "bicycle", "diff_drive_motors"]
CHANNELS = "output.channels=[coordinates, poses, contacts]"

failures = []


def check(ok, what):
    if not ok:
        failures.append(what)
        print("FAIL", what)
    return ok


def run(appell, *args):
    r = subprocess.run([appell, *args], capture_output=True, text=True,
                       env=dict(os.environ, OPENBLAS_NUM_THREADS="1"))
    if r.returncode != 0:
        raise SystemExit(f"appell {' '.join(args)} failed ({r.returncode}):\n{r.stderr}")
    return r


def read_csv(path):
    with open(path) as f:
        names = f.readline().strip().split(",")
        rows = [[float(x) for x in line.split(",")] for line in f if line.strip()]
    return names, rows


def quat_matrix(w, x, y, z):
    """Column-major 3 x 3 of a unit quaternion [w x y z]."""
    return [1 - 2 * (y * y + z * z), 2 * (x * y + w * z), 2 * (x * z - w * y),
            2 * (x * y - w * z), 1 - 2 * (x * x + z * z), 2 * (y * z + w * x),
            2 * (x * z + w * y), 2 * (y * z - w * x), 1 - 2 * (x * x + y * y)]


def make_page(appell, scenes, work, name, t_end, extra=()):
    scene = os.path.join(scenes, name + ".yaml")
    csv = os.path.join(work, name + ".csv")
    html = os.path.join(work, name + ".html")
    run(appell, "run", scene, "--t-end", str(t_end), "--set", CHANNELS, "--out", csv, "--quiet")
    run(appell, "view", scene, "--run", csv, "--out", html, *extra)
    return csv, html


def check_frames(page, name, names, rows):
    """World matrices and trace ends at four frames."""
    col = {n: i for i, n in enumerate(names)}
    bodies = page.eval("appellView.data.bodies.map(function (b) { return b.name; })")
    nf = len(rows)
    check(page.eval("appellView.data.nf") == nf, f"{name}: the page has {nf} frames")
    worst, worst_trace = 0.0, 0.0
    for k in sorted({0, nf // 3, (2 * nf) // 3, nf - 1}):
        state = page.eval(
            f"(appellView.setFrame({k}), appellView.bodies.map(function (g, b) {{"
            " var tr = appellView.traces[b], n = tr ? tr.geometry.drawRange.count : 0;"
            " return {m: g.matrixWorld.elements, n: n, end: tr ? Array.prototype.slice.call("
            "tr.geometry.attributes.position.array, 3 * n - 3, 3 * n) : null}; }))")
        row = rows[k]
        for b, body in enumerate(bodies):
            pos = [row[col[f"{body}.pos.{c}"]] for c in "xyz"]
            rot = quat_matrix(*[row[col[f"{body}.rot.{c}"]] for c in "wxyz"])
            m = state[b]["m"]
            err = max([abs(m[12 + i] - pos[i]) for i in range(3)] +
                      [abs(m[4 * j + i] - rot[3 * j + i]) for i in range(3) for j in range(3)])
            worst = max(worst, err)
            check(err <= 1e-9, f"{name}: frame {k}, body {body}: world matrix differs from the "
                  f"CSV by {err:.3g} (> 1e-9)")
            cx = f"{body}.contact.x"
            if cx in col:
                tr = state[b]
                check(tr["n"] == k + 1, f"{name}: frame {k}, {body}'s trace has {tr['n']} points")
                # The contacts channel gives x and y; z is 0 on the default ground, and on a
                # tilted plane or a ground sphere the terrain test checks the trace's height.
                want = [row[col[cx]], row[col[f"{body}.contact.y"]], 0.0]
                end = tr["end"] or [math.inf] * 3
                flat = "ground:" not in open(os.path.join(SCENE_DIR, name + ".yaml")).read()
                e = max(abs(end[i] - want[i]) / max(1.0, abs(want[i]))
                        for i in range(3 if flat else 2))
                worst_trace = max(worst_trace, e)
                check(e <= 2e-7, f"{name}: frame {k}, {body}'s trace ends at {end}, the CSV's "
                      f"contact point is {want} (relative {e:.3g} > 2e-7, float32)")
    return worst, worst_trace


def test_pages(appell, scenes, work):
    with cdp.Browser() as br:
        for name in SCENES:
            csv, html = make_page(appell, scenes, work, name, 1.0)
            page = br.open("file://" + html)
            page.eval("new Promise(function (r) { requestAnimationFrame(function () {"
                      " requestAnimationFrame(r); }); })")
            problems = page.problems()
            check(not problems, f"{name}: console messages: {problems}")
            names, rows = read_csv(csv)
            worst, wt = check_frames(page, name, names, rows)
            print(f"{name}: {len(rows)} frames, max |world matrix - CSV| {worst:.2e}, "
                  f"trace end {wt:.2e}, console clean: {not problems}")
            problems = page.problems()
            check(not problems, f"{name}: console messages after scrubbing: {problems}")


def test_pixels(appell, scenes, work):
    csv, html = make_page(appell, scenes, work, "rolling_disk", 3.0)
    names, rows = read_csv(csv)
    with cdp.Browser() as br:
        page = br.open("file://" + html, width=1000, height=700)
        nf = len(rows)
        k1 = nf // 6
        # A fixed camera, three times farther than the page's first view.
        page.eval("(function (v) { v.state.follow = -1; v.camera.position.sub(v.controls.target)"
                  ".multiplyScalar(3).add(v.controls.target); v.controls.update(); return 0; })"
                  "(appellView)")

        def shot(k):
            page.eval(f"(appellView.setFrame({k}), appellView.render(), 0)")
            page.eval("new Promise(function (r) { requestAnimationFrame(function () {"
                      " requestAnimationFrame(r); }); })")
            return cdp.png_pixels(page.screenshot())

        p1 = page.eval(f"appellView.project.apply(null, Array.prototype.slice.call("
                       f"appellView.poses, {7 * k1}, {7 * k1 + 3}))")
        # The second frame: the first after k1 whose disk centre is 150 px away and in view.
        view_w = page.eval("appellView.renderer.domElement.clientWidth")
        view_h = page.eval("appellView.renderer.domElement.clientHeight")
        c1 = page.eval(f"Array.prototype.slice.call(appellView.poses, {7 * k1}, {7 * k1 + 3})")
        top = page.eval(f"appellView.project({c1[0]}, {c1[1]}, {c1[2] + 0.5})")
        r_px = math.hypot(top[0] - p1[0], top[1] - p1[1])   # the disk's radius is 0.5 m
        for k2 in range(k1 + 1, nf):
            p2 = page.eval(f"appellView.project.apply(null, Array.prototype.slice.call("
                           f"appellView.poses, {7 * k2}, {7 * k2 + 3}))")
            if math.hypot(p1[0] - p2[0], p1[1] - p2[1]) > 3 * r_px:
                break
        # A ground point far from every position of the disk and its trace.
        col = {n: i for i, n in enumerate(names)}
        path = [(r[col["disk.pos.x"]], r[col["disk.pos.y"]]) for r in rows]
        xs, ys = [p[0] for p in path], [p[1] for p in path]
        far = (min(xs) - 1.0, max(ys) + 1.0)
        far_px = page.eval(f"appellView.project({far[0]}, {far[1]}, 0)")
        w, h, a = shot(k1)
        _, _, b = shot(k2)
        for p in (p1, p2, far_px):
            check(0 <= p[0] < view_w and 0 <= p[1] < view_h, f"pixel {p} inside the 3-D view")
        moved = [a[int(p1[1])][int(p1[0])], b[int(p1[1])][int(p1[0])]]
        still = [a[int(far_px[1])][int(far_px[0])], b[int(far_px[1])][int(far_px[0])]]
        dist = math.hypot(p1[0] - p2[0], p1[1] - p2[1])
        print(f"disk centre at frame {k1}: pixel {p1[0]:.1f}, {p1[1]:.1f} -> {moved}; "
              f"moved {dist:.0f} px (disk radius {r_px:.0f} px) by frame {k2}; ground point {far_px[0]:.1f}, {far_px[1]:.1f}"
              f" -> {still}")
        check(dist > 3 * r_px > 6, f"the disk's image (radius {r_px:.1f} px) moved {dist:.1f} px "
              f"between the frames")
        check(moved[0] != moved[1], "the pixel where the disk was differs between the shots")
        check(still[0] == still[1], "the pixel where nothing moved is the same in both shots")
        check(not page.problems(), f"console: {page.problems()}")


def test_events(appell, scenes, work):
    scene = os.path.join(scenes, "rolling_disk.yaml")
    csv = os.path.join(work, "stopped.csv")
    run(appell, "run", scene, "--t-end", "2", "--set", CHANNELS, "--out", csv, "--quiet")
    record = {"status": "stopped by event tilt_low", "events": [
        {"name": "tilt_low", "t": 1.25, "action": "stop"},
        {"name": "touch", "t": 0.5, "action": "log"}]}
    with open(os.path.join(work, "stopped.run.json"), "w") as f:
        json.dump(record, f)
    html = os.path.join(work, "stopped.html")
    run(appell, "view", scene, "--run", csv, "--out", html)
    with cdp.Browser() as br:
        page = br.open("file://" + html)
        marks = page.eval("Array.prototype.map.call(document.querySelectorAll('.event-mark'),"
                          " function (m) { var r = m.getBoundingClientRect(),"
                          " p = document.getElementById('marks').getBoundingClientRect();"
                          " return {name: m.dataset.name, t: Number(m.dataset.t),"
                          " frac: (r.left + r.width / 2 - p.left) / p.width,"
                          " visible: r.width > 0 && r.height > 0}; })")
        status = page.eval("document.querySelector('#info .status').textContent")
        print(f"event marks {marks}; status '{status}'")
        check(len(marks) == 2, f"two event marks on the timeline (got {len(marks)})")
        for m, e in zip(sorted(marks, key=lambda m: m["t"]), sorted(record["events"],
                                                                     key=lambda e: e["t"])):
            check(m["name"] == e["name"] and m["t"] == e["t"], f"mark {m} is event {e}")
            check(abs(m["frac"] - e["t"] / 2.0) < 0.01 and m["visible"],
                  f"mark {m['name']} drawn at {m['frac']:.4f} of the timeline, "
                  f"expected {e['t'] / 2.0:.4f}")
        check(status == "status: " + record["status"], f"status shown: {status}")
        # Playback: from the scrubbed frame 50 at 10x the frame advances; paused it stays.
        page.eval("(appellView.setFrame(50), document.getElementById('speed').value = '10',"
                  " document.getElementById('speed').dispatchEvent(new Event('change')),"
                  " document.getElementById('play').click(), 0)")
        moved = page.eval("new Promise(function (r) { var t0 = performance.now();"
                          " (function poll() { var f = appellView.state.frame;"
                          " if (f > 50 || performance.now() - t0 > 20000) r(f);"
                          " else setTimeout(poll, 50); })(); })")
        page.eval("(document.getElementById('play').click(), 0)")
        f1 = page.eval("appellView.state.frame")
        page.eval("new Promise(function (r) { setTimeout(r, 500); })")
        f2 = page.eval("appellView.state.frame")
        print(f"playback at 10x from frame 50: frame {moved}; paused at {f1}, then {f2}")
        check(moved > 50 and f1 == f2 and page.eval("appellView.state.speed") == 10,
              f"play advances ({moved}) and pause holds ({f1}, {f2})")
        check(not page.problems(), f"console: {page.problems()}")


def test_errors(appell, scenes, work):
    scene = os.path.join(scenes, "rolling_disk.yaml")
    good, nocoord, bad = (os.path.join(work, n) for n in ("good.csv", "nocoord.csv", "bad.csv"))
    run(appell, "run", scene, "--t-end", "0.1", "--out", good, "--quiet")
    run(appell, "run", scene, "--t-end", "0.1", "--set", "output.channels=[energy]", "--out",
        nocoord, "--quiet")
    with open(bad, "w") as f:
        f.write("t,disk.x\n0,1\n0.1,oops\n")
    out = os.path.join(work, "out.html")
    cases = [(["view", scene, "--run", nocoord, "--out", out], "no column disk.x"),
             (["view", scene, "--run", good, "--out", out, "--plot", "disk.tilx"],
              "--plot disk.tilx: no such column"),
             (["view", scene, "--run", bad, "--out", out], "bad.csv:3: not an appell CSV row"),
             (["view", scene, "--run", good, "--t-end", "1", "--out", out], "--t-end is a run"),
             (["export", scene, "--run", good, "--format", "obj", "--out", out],
              "--format obj: the only format is gltf")]
    for args, what in cases:
        r = subprocess.run([appell, *args], capture_output=True, text=True)
        print(f"appell {args[0]} ... {args[-1]}: exit {r.returncode}: {r.stderr.strip()}")
        check(r.returncode == 2 and what in r.stderr and len(r.stderr.splitlines()) == 1,
              f"{args}: exit {r.returncode}, message {r.stderr!r} (want 2 and '{what}')")
        check(not os.path.exists(out), f"{args}: no output file")


def glb_parse(path):
    data = open(path, "rb").read()
    magic, version, length = struct.unpack("<III", data[:12])
    check(magic == 0x46546C67 and version == 2 and length == len(data), "GLB header")
    jlen, _ = struct.unpack("<II", data[12:20])
    doc = json.loads(data[20:20 + jlen])
    blen, _ = struct.unpack("<II", data[20 + jlen:28 + jlen])
    return doc, data[28 + jlen:28 + jlen + blen]


def accessor(doc, binary, i):
    a = doc["accessors"][i]
    v = doc["bufferViews"][a["bufferView"]]
    n = {"SCALAR": 1, "VEC3": 3, "VEC4": 4}[a["type"]]
    off = v.get("byteOffset", 0) + a.get("byteOffset", 0)
    flat = struct.unpack_from(f"<{a['count'] * n}f", binary, off)
    return [flat[i * n:(i + 1) * n] for i in range(a["count"])]


def test_gltf(appell, scenes, work):
    node = shutil.which("node")
    modules = os.path.join(HERE, "node_modules", "gltf-validator")
    if not node:
        print("SKIP: node is not installed")
        raise SystemExit(77)
    if not os.path.isdir(modules):
        raise SystemExit(f"{modules} is missing: scripts/setup installs it (npm ci in "
                         f"tests/viewer)")
    scene = os.path.join(scenes, "bicycle.yaml")
    csv = os.path.join(work, "bicycle_gltf.csv")
    glb = os.path.join(work, "bicycle.glb")
    run(appell, "run", scene, "--t-end", "3", "--set", CHANNELS, "--out", csv, "--quiet")
    run(appell, "export", scene, "--run", csv, "--format", "gltf", "--out", glb)
    js = ("const v = require(process.argv[1]); const fs = require('fs');"
          "v.validateBytes(new Uint8Array(fs.readFileSync(process.argv[2])))"
          ".then(r => console.log(JSON.stringify(r.issues)))"
          ".catch(e => { console.error(e); process.exit(1); });")
    r = subprocess.run([node, "-e", js, modules, glb], capture_output=True, text=True)
    check(r.returncode == 0, f"the validator ran: {r.stderr}")
    issues = json.loads(r.stdout) if r.returncode == 0 else {"numErrors": -1}
    print(f"gltf-validator: {issues.get('numErrors')} errors, {issues.get('numWarnings')} "
          f"warnings, {issues.get('numInfos')} infos; {os.path.getsize(glb)} bytes")
    check(issues.get("numErrors") == 0, f"validator errors: {issues}")
    doc, binary = glb_parse(glb)
    names, rows = read_csv(csv)
    col = {n: i for i, n in enumerate(names)}
    anim = doc["animations"][0]
    worst = 0.0
    for ch in anim["channels"]:
        body = doc["nodes"][ch["target"]["node"]]["name"]
        s = anim["samplers"][ch["sampler"]]
        times, vals = accessor(doc, binary, s["input"]), accessor(doc, binary, s["output"])
        check(len(times) == len(rows), f"{body}: {len(times)} samples for {len(rows)} rows")
        keys = ([f"{body}.pos.{c}" for c in "xyz"] if ch["target"]["path"] == "translation"
                else [f"{body}.rot.{c}" for c in "xyzw"])
        for (t,), v, row in zip(times, vals, rows):
            ref = [row[col[k]] for k in keys] + [row[0] - rows[0][0]]
            got = list(v) + [t]
            # float32 rounding of each value: |f32(x) - x| <= 2^-24 |x|; 1e-12 covers the CSV's
            # 15 digits of q behind the rebuilt poses.
            worst = max([worst] + [abs(got[i] - ref[i]) / (2.0 ** -24 * abs(ref[i]) + 1e-12)
                                   for i in range(len(ref))])
    print(f"glTF samples vs CSV poses: max |sample - CSV| / (2^-24 |CSV| + 1e-12) = {worst:.3g}")
    check(worst <= 1.0, f"glTF samples differ from the CSV by more than float32 rounding "
          f"({worst:.3g})")


TERRAIN = {"ball_incline": ("plane", 0.1), "ball_bowl": ("sphere", 0.1),
           "ball_bumps": ("heightfield", 0.1)}


def bumps_h(x, y):
    """The height field of examples/scenes/ball_bumps.yaml (its z expression)."""
    e = math.exp
    return (0.05 * e(-((x - 1) ** 2 + y ** 2) / 0.1) -
            0.03 * e(-((x - 1.8) ** 2 + (y - 0.4) ** 2) / 0.15) +
            0.04 * e(-((x - 2.5) ** 2 + (y + 0.3) ** 2) / 0.08))


def ground_distance(g, pos):
    """Signed distance of pos from the drawn ground g (its world matrix, column-major); for
    the height field, the distance to the nearest drawn vertex (within the grid spacing of the
    surface's)."""
    m = g["m"]
    if g["kind"] == "heightfield":
        v = g["vertices"]
        return math.sqrt(min((v[i] - pos[0]) ** 2 + (v[i + 1] - pos[1]) ** 2 +
                             (v[i + 2] - pos[2]) ** 2 for i in range(0, len(v), 3)))
    if g["kind"] == "plane":
        n, o = m[8:11], m[12:15]
        return sum(n[i] * (pos[i] - o[i]) for i in range(3))
    return g["radius"] - math.dist(pos, m[12:15])   # inside the bowl: R - |p - c|


def check_ground_mesh(appell, scenes, work, name, kind, r_ball, glb_path, csv, node):
    scene = os.path.join(scenes, name + ".yaml")
    run(appell, "export", scene, "--run", csv, "--format", "gltf", "--out", glb_path)
    js = ("const v = require(process.argv[1]); const fs = require('fs');"
          "v.validateBytes(new Uint8Array(fs.readFileSync(process.argv[2])))"
          ".then(r => console.log(JSON.stringify(r.issues)))")
    modules = os.path.join(HERE, "node_modules", "gltf-validator")
    r = subprocess.run([node, "-e", js, modules, glb_path], capture_output=True, text=True)
    issues = json.loads(r.stdout) if r.returncode == 0 else {"numErrors": -1}
    check(issues.get("numErrors") == 0, f"{name}: glTF validator errors: {issues}")
    doc, binary = glb_parse(glb_path)
    ground = [n for n in doc["nodes"] if n["name"] == "ground"]
    check(len(ground) == 1, f"{name}: one ground node in the glTF")
    pos = accessor(doc, binary, doc["meshes"][ground[0]["mesh"]]["primitives"][0]["attributes"]
                   ["POSITION"])
    return pos


def test_terrain(appell, scenes, work):
    node = shutil.which("node")
    with cdp.Browser() as br:
        for name, (kind, r_ball) in TERRAIN.items():
            csv, html = make_page(appell, scenes, work, name, 1.0)
            page = br.open("file://" + html, width=1000, height=700)
            page.eval("new Promise(function (r) { requestAnimationFrame(function () {"
                      " requestAnimationFrame(r); }); })")
            check(not page.problems(), f"{name}: console messages: {page.problems()}")
            names, rows = read_csv(csv)
            check_frames(page, name, names, rows)
            grounds = page.eval("appellView.grounds.map(function (g) { return {kind: g.kind,"
                                " m: g.object.matrixWorld.elements, radius: g.kind == 'sphere' ?"
                                " g.object.geometry.parameters.radius : 0,"
                                " side: g.surface.material.side, vertices: g.kind =="
                                " 'heightfield' ? Array.from(g.surface.geometry.attributes"
                                ".position.array) : [], d: g.kind == 'heightfield' ?"
                                " appellView.data.grounds[0].d : 0}; })")
            check(len(grounds) == 1 and grounds[0]["kind"] == kind,
                  f"{name}: the page draws one {kind}: {[g['kind'] for g in grounds]}")
            g = grounds[0]
            col = {n: i for i, n in enumerate(names)}
            ball = names[1].split(".")[0]
            worst = max(abs(ground_distance(g, [row[col[f"{ball}.pos.{c}"]] for c in "xyz"])
                            - r_ball) for row in rows)
            if kind == "heightfield":   # no vertex inside the ball, one within the spacing
                dist = [ground_distance(g, [row[col[f"{ball}.pos.{c}"]] for c in "xyz"])
                        for row in rows[::5]]
                v = g["vertices"]
                zerr = max(abs(v[i + 2] - bumps_h(v[i], v[i + 1])) for i in range(0, len(v), 3))
                worst = max(abs(x - r_ball) for x in dist)
                check(min(dist) >= r_ball - 1e-6 and max(dist) <= r_ball + g["d"],
                      f"{name}: the ball centre is {min(dist):.4g}..{max(dist):.4g} from the "
                      f"drawn vertices (radius {r_ball}, spacing {g['d']:.3g})")
                check(zerr <= 1e-6, f"{name}: drawn heights {zerr:.3g} off h(x, y)")
            else:
                check(worst <= 1e-9, f"{name}: the ball is {worst:.3g} off the drawn ground")
            if kind == "heightfield":
                pass
            elif kind == "plane":
                want = [0, -math.sin(math.radians(25)), math.cos(math.radians(25))]
                err = max(abs(g["m"][8 + i] - want[i]) for i in range(3))
                check(err <= 1e-12, f"{name}: drawn normal {g['m'][8:11]} (scene {want})")
            else:
                err = max(abs(g["m"][12 + i] - c) for i, c in enumerate([0, 0, 1]))
                check(err <= 1e-12 and g["radius"] == 1 and g["side"] == 1,
                      f"{name}: drawn sphere at {g['m'][12:15]}, radius {g['radius']}, side "
                      f"{g['side']} (scene: centre (0, 0, 1), radius 1, inside: BackSide = 1)")
            # A ground point away from the ball in the 3-D view: on the incline 0.25 m from the
            # ball's contact point at frame 0, in the bowl 25 degrees up its wall: the first
            # direction whose pixel is in the view and 1.5 ball radii from the ball's image.
            page.eval("(appellView.setFrame(0), appellView.render(), 0)")
            view_w = page.eval("appellView.renderer.domElement.clientWidth")
            view_h = page.eval("appellView.renderer.domElement.clientHeight")
            c0 = [rows[0][col[f"{ball}.pos.{c}"]] for c in "xyz"]
            pc, ptop = (page.eval(f"appellView.project({p[0]}, {p[1]}, {p[2]})")
                        for p in (c0, [c0[0], c0[1], c0[2] + r_ball]))
            r_px = math.hypot(pc[0] - ptop[0], pc[1] - ptop[1])
            if kind == "plane":
                n = g["m"][8:11]
                t1 = [1, 0, 0]
                t2 = [n[1] * t1[2] - n[2] * t1[1], n[2] * t1[0] - n[0] * t1[2],
                      n[0] * t1[1] - n[1] * t1[0]]
                cands = [[c0[i] - r_ball * n[i] + 0.25 * (math.cos(a) * t1[i] +
                          math.sin(a) * t2[i]) for i in range(3)]
                         for a in [k * math.pi / 6 for k in range(12)]]
            elif kind == "heightfield":   # the surface 0.25 m around the ball
                cands = [[c0[0] + 0.25 * math.cos(a), c0[1] + 0.25 * math.sin(a),
                          bumps_h(c0[0] + 0.25 * math.cos(a), c0[1] + 0.25 * math.sin(a))]
                         for a in [k * math.pi / 6 for k in range(12)]]
            else:   # the bowl's wall 25 degrees up from its bottom
                s25, c25 = math.sin(math.radians(25)), math.cos(math.radians(25))
                cands = [[s25 * math.cos(a), s25 * math.sin(a), 1 - c25]
                         for a in [k * math.pi / 6 for k in range(12)]]
            at, px = None, None
            for cand in cands:
                q = page.eval(f"appellView.project({cand[0]}, {cand[1]}, {cand[2]})")
                if (0 <= q[0] < view_w and 0 <= q[1] < view_h and
                        math.hypot(q[0] - pc[0], q[1] - pc[1]) > 1.5 * r_px):
                    at, px = cand, q
                    break
            check(at is not None, f"{name}: a ground point near the ball in the view")
            w, h, pix = cdp.png_pixels(page.screenshot())
            got = pix[int(px[1])][int(px[0])] if at else (0xdf, 0xe6, 0xee)
            check(tuple(got[:3]) != (0xdf, 0xe6, 0xee), f"{name}: the ground point {at} at pixel "
                  f"{px} shows the background colour {got}")
            print(f"{name}: {kind} drawn, ball off the drawn ground by {worst:.2e}; ground pixel "
                  f"{got}")
            if node and os.path.isdir(os.path.join(HERE, "node_modules", "gltf-validator")):
                pos = check_ground_mesh(appell, scenes, work, name, kind, r_ball,
                                        os.path.join(work, name + ".glb"), csv, node)
                gm = dict(g, m=g["m"][:12] + ([0, 0, 0] if kind == "plane" else [0, 0, 1]) +
                          [1], radius=1)
                off = max(abs(ground_distance(gm, p) if kind != "heightfield" else
                              p[2] - bumps_h(p[0], p[1])) for p in pos)
                check(off <= 1e-6, f"{name}: the glTF ground is {off:.3g} off the surface")
                print(f"{name}: glTF ground mesh of {len(pos)} vertices, {off:.2e} off")


SCENE_DIR = ""   # the example scenes' folder (main)


def main():
    global SCENE_DIR
    appell, scenes, work, what = sys.argv[1:5]
    SCENE_DIR = scenes
    os.makedirs(work, exist_ok=True)
    if what not in ("gltf", "errors") and not cdp.find_chromium():
        print("SKIP: chromium is not installed (scripts/setup installs Debian's chromium)")
        return 77
    {"pages": test_pages, "pixels": test_pixels, "events": test_events,
     "gltf": test_gltf, "errors": test_errors, "terrain": test_terrain}[what](appell, scenes,
                                                                             work)
    print(f"{what}: {len(failures)} failures")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
