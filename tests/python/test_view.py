"""Result.view and Result._repr_html_ (python/appell/_view.py, docs/viewer.md).

Reference: the run's own columns. The page embeds, for every frame, the pose the library
rebuilds from the coordinates; for the rolling disk on its plane-contact joint the body origin's
x, y are the joint coordinates disk.x, disk.y and the height is r sin(tilt) (r = 0.5 m)."""

import base64
import json
import math
import re
import struct

import appell
from conftest import SCENES


def _data(page):
    m = re.search(r'<script type="application/json" id="appell-data">(.*?)</script>', page, re.S)
    assert m, "the page embeds its data"
    return json.loads(m.group(1))


def _f64(b64):
    raw = base64.b64decode(b64)
    return struct.unpack(f"<{len(raw) // 8}d", raw)


def test_view_writes_the_page(tmp_path):
    m = appell.load(SCENES / "rolling_disk.yaml")
    res = appell.Simulation(m).run(t_end=0.5, dt=0.05)
    out = res.view(tmp_path / "disk.html", plots=["disk.tilt"])
    page = open(out).read()
    d = _data(page)
    assert d["nf"] == len(res) and d["nb"] == 1
    assert [p["name"] for p in d["plots"]] == ["disk.tilt"]
    t, pose = _f64(d["t"]), _f64(d["pose"])
    for r in range(len(res)):
        assert t[r] == res.t[r]
        assert abs(pose[7 * r] - res["disk.x"][r]) < 1e-12
        assert abs(pose[7 * r + 1] - res["disk.y"][r]) < 1e-12
        assert abs(pose[7 * r + 2] - 0.5 * math.sin(res["disk.tilt"][r])) < 1e-12
    assert "http://" not in page.split("<script>", 1)[0] and "<script src" not in page


def test_repr_html_is_the_page():
    m = appell.load(SCENES / "rolling_disk.yaml")
    res = appell.Simulation(m).run(t_end=0.2, dt=0.1)
    h = res._repr_html_()
    assert h.startswith("<iframe") and "srcdoc=" in h and "appell-data" in h
