"""The 3-D viewer from Python: Result.view(path) writes the self-contained HTML page of
`appell view` (docs/viewer.md), and a Result shows itself as that page in Jupyter
(_repr_html_). The page is made by the appell command: the Result's rows go to a CSV, the
model's scene text to a scene file, both in a temporary directory.

The appell command is found as $APPELL_EXE, then `appell` on PATH, then the build tree's
tools/appell next to this package (build/python/appell -> build/tools/appell)."""

import html as _html
import math as _math
import os as _os
import shutil as _shutil
import subprocess as _subprocess
import tempfile as _tempfile


def _appell_exe():
    exe = _os.environ.get("APPELL_EXE") or _shutil.which("appell")
    if exe:
        return exe
    here = _os.path.dirname(_os.path.abspath(__file__))
    built = _os.path.join(here, "..", "..", "tools", "appell")
    if _os.access(built, _os.X_OK):
        return _os.path.normpath(built)
    raise FileNotFoundError("the appell command is needed to draw the page: put it on PATH or "
                            "set APPELL_EXE")


def _number(x):
    x = float(x)
    return repr(x) if _math.isfinite(x) else ("nan" if x != x else ("inf" if x > 0 else "-inf"))


def _write_csv(res, path):
    """t, the coordinates (from res.q when the table lacks them) and the other columns."""
    names = list(res.columns)
    extra = [n for n in res.coordinate_names if n not in names]
    with open(path, "w") as f:
        f.write(",".join(names + extra) + "\n")
        for r in range(len(res)):
            vals = [_number(x) for x in res.table[r]]
            vals += [_number(res.q[r, res.coordinate_names.index(n)]) for n in extra]
            f.write(",".join(vals) + "\n")


def _page(res, out, plots=(), forces=False, title=None):
    model = getattr(res, "model", None)
    if model is None:
        raise ValueError("this Result does not know its model (make it with Simulation.run)")
    text, name, sets = model.source
    if not len(res):
        raise ValueError("the Result has no rows to show")
    with _tempfile.TemporaryDirectory(prefix="appell-view-") as tmp:
        scene = _os.path.join(tmp, "scene.yaml")
        csv = _os.path.join(tmp, "run.csv")
        with open(scene, "wb") as f:
            f.write(text if isinstance(text, bytes) else text.encode())
        _write_csv(res, csv)
        cmd = [_appell_exe(), "view", scene, "--run", csv, "--out", _os.fspath(out),
               "--title", title or name]
        for s in sets:
            cmd += ["--set", s]
        for p in plots:
            cmd += ["--plot", p]
        if forces:
            cmd.append("--forces")
        r = _subprocess.run(cmd, capture_output=True, text=True)
        if r.returncode != 0:
            raise RuntimeError(f"appell view failed ({r.returncode}): {r.stderr.strip()}")


def view(res, path, plots=(), forces=False, title=None):
    """Write the viewer page of this run to path (one self-contained HTML file: open it in a
    browser). plots: column names drawn beside the 3-D view; forces: contact-force arrows
    (needs the contact_forces channel). Returns path."""
    _page(res, path, plots, forces, title)
    return path


def repr_html(res):
    """The viewer page inline (an iframe whose srcdoc is the page), for Jupyter."""
    with _tempfile.TemporaryDirectory(prefix="appell-view-") as tmp:
        out = _os.path.join(tmp, "view.html")
        try:
            _page(res, out)
        except (ValueError, RuntimeError, FileNotFoundError) as e:
            return f"<pre>{_html.escape(repr(res))}\n(no viewer: {_html.escape(str(e))})</pre>"
        with open(out) as f:
            page = f.read()
    return ('<iframe style="width: 100%; height: 620px; border: 1px solid #ccc" '
            f'srcdoc="{_html.escape(page, quote=True)}"></iframe>')
