"""Headless Chromium driven through its DevTools protocol over a pipe (--remote-debugging-pipe:
JSON messages separated by NUL bytes on file descriptors 3 and 4), for the viewer's tests and
bench/bench_viewer.py. No network, no port: the browser is a child process of the test.

    with Browser() as b:
        page = b.open("file:///tmp/disk.html", width=1000, height=700)
        page.eval("appellView.state.frame")
        page.console          # [(level, text)] of every console message, warning and error
"""
import base64
import json
import os
import shutil
import subprocess
import tempfile
import time


def find_chromium():
    for name in ("chromium", "chromium-browser", "google-chrome"):
        path = shutil.which(name)
        if path:
            return path
    return None


class Error(Exception):
    pass


class Browser:
    def __init__(self, timeout=60.0):
        exe = find_chromium()
        if not exe:
            raise Error("chromium not found (scripts/setup installs Debian's chromium)")
        self.profile = tempfile.mkdtemp(prefix="appell-cdp-")
        r_child, self.w = os.pipe()      # we write commands, the browser reads fd 3
        self.r, w_child = os.pipe()      # the browser writes fd 4, we read
        args = [exe, "--headless", "--no-sandbox", "--use-angle=swiftshader",
                "--enable-unsafe-swiftshader", "--remote-debugging-pipe", "--no-first-run",
                "--no-default-browser-check", "--disable-extensions", "--hide-scrollbars",
                "--mute-audio", "--disable-background-networking", "--disable-sync",
                "--disable-component-update", "--user-data-dir=" + self.profile, "about:blank"]

        # The browser's ends go to fds 3 and 4; move them out of the way first (they may
        # themselves be 3 or 4).
        def fds():
            a, b = os.dup(r_child), os.dup(w_child)
            os.dup2(a, 3)
            os.dup2(b, 4)
            os.close(a)
            os.close(b)

        self.log = tempfile.TemporaryFile()
        self.proc = subprocess.Popen(args, pass_fds=(3, 4), preexec_fn=fds,
                                     stdin=subprocess.DEVNULL, stdout=self.log, stderr=self.log)
        os.close(r_child)
        os.close(w_child)
        self.timeout = timeout
        self.next_id = 0
        self.buf = b""
        self.pending = []

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()

    def close(self):
        try:
            self.send("Browser.close")
        except Exception:
            pass
        try:
            self.proc.wait(timeout=10)
        except subprocess.TimeoutExpired:
            self.proc.kill()
            self.proc.wait()
        for fd in (self.w, self.r):
            try:
                os.close(fd)
            except OSError:
                pass
        shutil.rmtree(self.profile, ignore_errors=True)

    def _read_message(self, deadline):
        while b"\0" not in self.buf:
            if time.monotonic() > deadline:
                raise Error("timeout waiting for the browser")
            chunk = os.read(self.r, 1 << 20)
            if not chunk:
                raise Error("the browser closed its pipe")
            self.buf += chunk
        msg, self.buf = self.buf.split(b"\0", 1)
        return json.loads(msg)

    def send(self, method, params=None, session=None, wait=True):
        self.next_id += 1
        mid = self.next_id
        msg = {"id": mid, "method": method, "params": params or {}}
        if session:
            msg["sessionId"] = session
        os.write(self.w, json.dumps(msg).encode() + b"\0")
        if not wait:
            return None
        deadline = time.monotonic() + self.timeout
        while True:
            m = self._read_message(deadline)
            if m.get("id") == mid:
                if "error" in m:
                    raise Error(f"{method}: {m['error']}")
                return m.get("result", {})
            self.pending.append(m)

    def events(self):
        """Messages that arrived while waiting for replies, then cleared."""
        out, self.pending = self.pending, []
        return out

    def open(self, url, width=1200, height=760):
        target = self.send("Target.createTarget", {"url": "about:blank"})["targetId"]
        session = self.send("Target.attachToTarget", {"targetId": target, "flatten": True})
        page = Page(self, session["sessionId"])
        page.init(width, height)
        page.navigate(url)
        return page


class Page:
    def __init__(self, browser, session):
        self.b = browser
        self.session = session
        self.console = []

    def cmd(self, method, params=None):
        r = self.b.send(method, params, session=self.session)
        self._collect()
        return r

    def _collect(self):
        for m in self.b.events():
            if m.get("sessionId") != self.session:
                continue
            method, p = m.get("method"), m.get("params", {})
            if method == "Runtime.consoleAPICalled":
                text = " ".join(str(a.get("value", a.get("description", ""))) for a in p["args"])
                self.console.append((p["type"], text))
            elif method == "Runtime.exceptionThrown":
                d = p["exceptionDetails"]
                self.console.append(("error", d.get("exception", {}).get("description",
                                                                         d.get("text", ""))))
            elif method == "Log.entryAdded":
                e = p["entry"]
                self.console.append((e["level"], e.get("text", "")))
            elif method == "Page.loadEventFired":
                self.loaded = True

    def init(self, width, height):
        self.cmd("Runtime.enable")
        self.cmd("Log.enable")
        self.cmd("Page.enable")
        self.cmd("Emulation.setDeviceMetricsOverride",
                 {"width": width, "height": height, "deviceScaleFactor": 1, "mobile": False})

    def navigate(self, url, timeout=60.0):
        self.loaded = False
        self.cmd("Page.navigate", {"url": url})
        deadline = time.monotonic() + timeout
        while not self.loaded:
            if time.monotonic() > deadline:
                raise Error(f"{url} did not load")
            self.cmd("Runtime.evaluate", {"expression": "1"})
            time.sleep(0.05)

    def eval(self, expr):
        """The JSON value of a JavaScript expression, a promise awaited (raises on an
        exception)."""
        r = self.cmd("Runtime.evaluate", {"expression": f"Promise.resolve({expr})"
                                          ".then(function (v) { return JSON.stringify(v); })",
                                          "returnByValue": True, "awaitPromise": True})
        if "exceptionDetails" in r:
            raise Error(f"{expr}: {r['exceptionDetails'].get('exception', {}).get('description')}")
        v = r["result"].get("value")
        return None if v is None else json.loads(v)

    def screenshot(self):
        """PNG bytes of the viewport."""
        r = self.cmd("Page.captureScreenshot", {"format": "png"})
        return base64.b64decode(r["data"])

    def problems(self):
        """Console messages at warning or error level."""
        self._collect()
        return [(lvl, text) for lvl, text in self.console
                if lvl in ("error", "warning", "warn", "assert")]


def png_pixels(data):
    """(width, height, rows) of an 8-bit RGB or RGBA PNG (what Chromium's screenshots are):
    rows[y][x] is an (r, g, b) tuple. Non-interlaced only."""
    import struct
    import zlib
    if data[:8] != b"\x89PNG\r\n\x1a\n":
        raise Error("not a PNG")
    pos, idat, width = 8, b"", 0
    while pos < len(data):
        n, kind = struct.unpack(">I4s", data[pos:pos + 8])
        body = data[pos + 8:pos + 8 + n]
        if kind == b"IHDR":
            width, height, depth, ctype, _, _, interlace = struct.unpack(">IIBBBBB", body)
            if depth != 8 or ctype not in (2, 6) or interlace:
                raise Error(f"PNG kind not handled (depth {depth}, colour type {ctype})")
            bpp = 3 if ctype == 2 else 4
        elif kind == b"IDAT":
            idat += body
        pos += 12 + n
    raw = zlib.decompress(idat)
    stride = width * bpp
    rows, prev = [], bytearray(stride)
    for y in range(height):
        f, line = raw[y * (stride + 1)], bytearray(raw[y * (stride + 1) + 1:(y + 1) * (stride + 1)])
        for i in range(stride):
            a = line[i - bpp] if i >= bpp else 0
            b = prev[i]
            c = prev[i - bpp] if i >= bpp else 0
            if f == 1:
                line[i] = (line[i] + a) & 255
            elif f == 2:
                line[i] = (line[i] + b) & 255
            elif f == 3:
                line[i] = (line[i] + (a + b) // 2) & 255
            elif f == 4:
                p = a + b - c
                pa, pb, pc = abs(p - a), abs(p - b), abs(p - c)
                line[i] = (line[i] + (a if pa <= pb and pa <= pc else b if pb <= pc else c)) & 255
        rows.append([tuple(line[x * bpp:x * bpp + 3]) for x in range(width)])
        prev = line
    return width, height, rows
