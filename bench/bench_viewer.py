#!/usr/bin/env python3
"""Benchmark of appell view (docs/viewer.md, docs/performance.md): file sizes and playback
frame time in headless Chromium.

    bench/bench_viewer.py [--appell build/tools/appell] [--frames 10000] [--measure N] [--out DIR]

1. Sizes: the viewer page of the bicycle (examples/scenes/bicycle.yaml) run for 10 s at 100
   frames per second (1001 frames), its glTF export, and the rolling disk's page (15 s).
2. Playback: a scene of 20 rolling disks (written here) run for --frames frames at 100 per
   second; in headless Chromium (1280 x 720, WebGL on SwiftShader, the CPU renderer: no GPU on
   this machine) every frame is shown once: appellView.setFrame(i) (the pose update), then a
   render, then a one-pixel readPixels that waits for the GPU work to finish. Reports the median,
   95th percentile and mean per-frame time of the update alone and of update + render, and the
   share of frames under 16.7 ms (60 frames per second). --measure N times only the first N
   frames of the page (default all); progress goes to standard error.

Prints a table and writes DIR/viewer_bench.csv (DIR default build/bench-viewer)."""
import argparse
import csv
import os
import statistics
import subprocess
import sys
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, os.path.join(ROOT, "tests", "viewer"))
import cdp  # noqa: E402


def twenty_disks(path, t_end):
    lines = ["name: twenty_disks", "description: 20 rolling disks (bench/bench_viewer.py)",
             "bodies:"]
    lines += [f"  d{i}: {{mass: 1, shape: {{kind: disk, radius: 0.3}}, inertia: uniform}}"
              for i in range(20)]
    lines += ["joints:"] + [f"  d{i}: {{kind: plane_contact}}" for i in range(20)]
    lines += ["constraints:"] + [f"  r{i}: {{kind: rolling, body: d{i}}}" for i in range(20)]
    lines += ["effects:", "  gravity: {kind: gravity}", "initial:"]
    lines += [f"  d{i}: {{x: {(i % 5) * 2.0}, y: {(i // 5) * 2.0}, tilt: {70 + i}*deg, "
              f"spin_rate: -6, heading_rate: {2 + 0.1 * i}}}" for i in range(20)]
    lines += [f"simulation: {{rtol: 1e-6, atol: 1e-8, t_end: {t_end}}}",
              "output: {interval: 0.01, channels: [coordinates]}"]
    with open(path, "w") as f:
        f.write("\n".join(lines) + "\n")


def appell(exe, *args):
    subprocess.run([exe, *args], check=True, stderr=subprocess.DEVNULL,
                   env=dict(os.environ, OPENBLAS_NUM_THREADS="1"))


def sizes(exe, out):
    scenes = os.path.join(ROOT, "examples", "scenes")
    bike_csv, bike_html = os.path.join(out, "bicycle.csv"), os.path.join(out, "bicycle.html")
    appell(exe, "view", os.path.join(scenes, "bicycle.yaml"), "--t-end", "10", "--interval",
           "0.01", "--out", bike_html)
    appell(exe, "export", os.path.join(scenes, "bicycle.yaml"), "--run", bike_csv, "--format",
           "gltf", "--out", os.path.join(out, "bicycle.glb"))
    appell(exe, "view", os.path.join(scenes, "rolling_disk.yaml"), "--out",
           os.path.join(out, "rolling_disk.html"))
    return [(f, os.path.getsize(os.path.join(out, f)))
            for f in ("bicycle.html", "bicycle.glb", "rolling_disk.html")]


def summary(xs):
    xs = sorted(xs)
    return (statistics.median(xs), xs[int(0.95 * (len(xs) - 1))], statistics.fmean(xs),
            sum(x < 1000 / 60 for x in xs) / len(xs))


def playback(exe, out, frames, measure):
    scene, html = os.path.join(out, "twenty.yaml"), os.path.join(out, "twenty.html")
    twenty_disks(scene, (frames - 1) / 100)
    appell(exe, "view", scene, "--out", html)
    size = os.path.getsize(html)
    with cdp.Browser(timeout=300) as b:
        t = time.monotonic()
        page = b.open("file://" + html, width=1280, height=720)
        load = time.monotonic() - t
        nf = page.eval("appellView.data.nf")
        page.eval("(function (v) { v.state.playing = false;"
                  " v.gl = v.renderer.getContext(); v.px = new Uint8Array(4); return 0; })"
                  "(appellView)")
        upd, full = [], []
        nm = min(nf, measure or nf)
        for start in range(0, nm, 500):
            r = page.eval(
                f"(function (v) {{ var u = [], f = [];"
                f" for (var i = {start}; i < Math.min({start + 500}, {nm}); i++) {{"
                f"  var a = performance.now(); v.setFrame(i); var b = performance.now();"
                f"  v.render(); v.gl.readPixels(0, 0, 1, 1, v.gl.RGBA, v.gl.UNSIGNED_BYTE, v.px);"
                f"  var c = performance.now(); u.push(b - a); f.push(c - a); }}"
                f" return [u, f]; }})(appellView)")
            upd += r[0]
            full += r[1]
            print(f"bench_viewer: {len(full)} of {nm} frames, median so far "
                  f"{statistics.median(full):.1f} ms", file=sys.stderr, flush=True)
    return nf, nm, size, load, summary(upd), summary(full)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--appell", default=os.path.join(ROOT, "build", "tools", "appell"))
    ap.add_argument("--frames", type=int, default=10000)
    ap.add_argument("--measure", type=int, default=0)
    ap.add_argument("--out", default=os.path.join(ROOT, "build", "bench-viewer"))
    a = ap.parse_args()
    os.makedirs(a.out, exist_ok=True)
    rows = [("size", f, n, "bytes") for f, n in sizes(a.appell, a.out)]
    nf, nm, size, load, upd, full = playback(a.appell, a.out, a.frames, a.measure)
    rows.append(("size", "twenty.html", size, "bytes"))
    rows.append(("load", "twenty.html", round(load, 2), "s"))
    for name, s in (("update", upd), ("update+render", full)):
        rows += [(name, "median", round(s[0], 3), "ms"), (name, "p95", round(s[1], 3), "ms"),
                 (name, "mean", round(s[2], 3), "ms"),
                 (name, "share under 16.7 ms", round(s[3], 4), "")]
    print(f"appell view: 20 bodies, {nf} frames ({nm} timed), headless Chromium (SwiftShader), "
          f"1280 x 720")
    for r in rows:
        print(f"  {r[0]:<14} {r[1]:<20} {r[2]:>12} {r[3]}")
    with open(os.path.join(a.out, "viewer_bench.csv"), "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["what", "item", "value", "unit"])
        w.writerows(rows)


if __name__ == "__main__":
    main()
