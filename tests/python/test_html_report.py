#!/usr/bin/env python3
"""vdbwrap wrap --html, end to end: wraps a corpus file (and a leaking one) with --html and
--report, loads each page in headless Chromium through the DevTools protocol and checks that
there are no console errors, that the 3-D view is drawn (the canvas area of a screenshot holds
more than the background), that every number on the page (elements with data-key) is the JSON
report's value at that key, and that a missing three.js is exit code 2 before any work.

Standard library only (the DevTools client below speaks just enough WebSocket). Exit code 77
(ctest SKIP_RETURN_CODE) when no Chromium is installed; scripts/install-deps.sh installs it."""
import argparse
import base64
import json
import os
import shutil
import socket
import struct
import subprocess
import sys
import tempfile
import time
import urllib.request
import zlib

FAILURES = []


def check(condition, message):
    if not condition:
        FAILURES.append(message)
        print("FAIL: " + message, file=sys.stderr)
    return condition


# ---- a minimal WebSocket client (RFC 6455: text frames out, masked; frames in, unmasked) ----
class WebSocket:
    def __init__(self, url):
        assert url.startswith("ws://")
        host_port, _, path = url[5:].partition("/")
        host, _, port = host_port.partition(":")
        self.sock = socket.create_connection((host, int(port)), timeout=120)
        key = base64.b64encode(os.urandom(16)).decode()
        self.sock.sendall(("GET /%s HTTP/1.1\r\nHost: %s\r\nUpgrade: websocket\r\nConnection: Upgrade\r\n"
                           "Sec-WebSocket-Key: %s\r\nSec-WebSocket-Version: 13\r\n\r\n" % (path, host_port, key)).encode())
        head = b""
        while b"\r\n\r\n" not in head:
            chunk = self.sock.recv(4096)
            if not chunk:
                raise RuntimeError("the DevTools socket closed during the handshake")
            head += chunk
        head, _, self.buffer = head.partition(b"\r\n\r\n")
        if b" 101 " not in head.split(b"\r\n")[0]:
            raise RuntimeError("no WebSocket upgrade: " + head.decode(errors="replace"))

    def _read(self, n):
        while len(self.buffer) < n:
            chunk = self.sock.recv(1 << 20)
            if not chunk:
                raise RuntimeError("the DevTools socket closed")
            self.buffer += chunk
        out, self.buffer = self.buffer[:n], self.buffer[n:]
        return out

    def send(self, text, opcode=0x1):
        payload = text.encode() if isinstance(text, str) else text
        header = bytes([0x80 | opcode])
        n = len(payload)
        if n < 126:
            header += bytes([0x80 | n])
        elif n < 1 << 16:
            header += bytes([0x80 | 126]) + struct.pack(">H", n)
        else:
            header += bytes([0x80 | 127]) + struct.pack(">Q", n)
        mask = os.urandom(4)
        self.sock.sendall(header + mask + bytes(b ^ mask[i % 4] for i, b in enumerate(payload)))

    def receive(self):
        message = b""
        while True:
            b0, b1 = self._read(2)
            opcode, n = b0 & 0x0F, b1 & 0x7F
            if n == 126:
                n = struct.unpack(">H", self._read(2))[0]
            elif n == 127:
                n = struct.unpack(">Q", self._read(8))[0]
            payload = self._read(n)
            if opcode == 0x9:  # ping
                self.send(payload, 0xA)
                continue
            if opcode == 0x8:
                raise RuntimeError("the DevTools socket was closed by the browser")
            message += payload
            if b0 & 0x80:
                return message.decode()


class DevTools:
    """One page of a headless Chromium, driven over the DevTools protocol."""

    def __init__(self, chromium, work):
        self.profile = tempfile.mkdtemp(prefix="chromium-", dir=work)
        self.process = subprocess.Popen(
            [chromium, "--headless", "--disable-gpu", "--no-sandbox", "--enable-unsafe-swiftshader",
             "--no-first-run", "--no-default-browser-check", "--user-data-dir=" + self.profile,
             "--remote-debugging-port=0", "--window-size=1400,900", "about:blank"],
            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        port_file = os.path.join(self.profile, "DevToolsActivePort")
        deadline = time.time() + 60
        while not (os.path.exists(port_file) and open(port_file).read().strip()):
            if time.time() > deadline or self.process.poll() is not None:
                raise RuntimeError("Chromium did not open its DevTools port")
            time.sleep(0.1)
        port = int(open(port_file).read().split()[0])
        pages = json.load(urllib.request.urlopen("http://127.0.0.1:%d/json/list" % port))
        page = [p for p in pages if p.get("type") == "page"][0]
        self.ws = WebSocket(page["webSocketDebuggerUrl"])
        self.next_id = 0
        self.events = []
        for domain in ("Runtime", "Log", "Page"):
            self.call(domain + ".enable")

    def call(self, method, **params):
        self.next_id += 1
        self.ws.send(json.dumps({"id": self.next_id, "method": method, "params": params}))
        while True:
            message = json.loads(self.ws.receive())
            if message.get("id") == self.next_id:
                if "error" in message:
                    raise RuntimeError("%s: %s" % (method, message["error"]))
                return message.get("result", {})
            if "method" in message:
                self.events.append(message)

    def evaluate(self, expression):
        result = self.call("Runtime.evaluate", expression=expression, returnByValue=True, awaitPromise=True)
        if "exceptionDetails" in result:
            raise RuntimeError("page script failed: %s" % result["exceptionDetails"])
        return result["result"].get("value")

    def errors(self):
        """The page's console errors and uncaught exceptions so far."""
        out = []
        for e in self.events:
            p = e.get("params", {})
            if e["method"] == "Runtime.exceptionThrown":
                d = p["exceptionDetails"]
                out.append("exception: %s %s" % (d.get("text", ""), d.get("exception", {}).get("description", "")))
            elif e["method"] == "Runtime.consoleAPICalled" and p.get("type") in ("error", "assert"):
                out.append("console.%s: %s" % (p["type"], " ".join(str(a.get("value", a.get("description", ""))) for a in p["args"])))
            elif e["method"] == "Log.entryAdded" and p["entry"].get("level") == "error":
                out.append("log: %s (%s)" % (p["entry"].get("text"), p["entry"].get("url", "")))
        return out

    def load(self, path):
        self.events = []
        self.call("Page.navigate", url="file://" + os.path.abspath(path))
        deadline = time.time() + 120
        while time.time() < deadline:
            state = self.evaluate("document.readyState === 'complete' ? document.body.getAttribute('data-viewer') : null")
            if state in ("ready", "error"):
                self.evaluate("new Promise(r => requestAnimationFrame(() => requestAnimationFrame(r)))")
                return state
            time.sleep(0.1)
        return "timeout"

    def screenshot(self, selector=None, scale=1.0):
        clip = None
        if selector:
            r = self.evaluate("(() => { const r = document.querySelector(%s).getBoundingClientRect();"
                              " return {x: r.x, y: r.y, width: r.width, height: r.height}; })()" % json.dumps(selector))
            clip = dict(r, scale=scale)
        params = {"format": "png"}
        if clip:
            params["clip"] = clip
        return base64.b64decode(self.call("Page.captureScreenshot", **params)["data"])

    def close(self):
        try:
            self.call("Browser.close")
        except Exception:
            pass
        try:
            self.process.wait(timeout=20)
        except subprocess.TimeoutExpired:
            self.process.kill()
        shutil.rmtree(self.profile, ignore_errors=True)


# ---- PNG pixels (8-bit RGB or RGBA, no interlace: what Chromium writes) ----
def png_pixels(data):
    assert data[:8] == b"\x89PNG\r\n\x1a\n", "not a PNG"
    pos, idat = 8, b""
    while pos < len(data):
        n, kind = struct.unpack(">I4s", data[pos:pos + 8])
        body = data[pos + 8:pos + 8 + n]
        if kind == b"IHDR":
            width, height, depth, colour, _, _, interlace = struct.unpack(">IIBBBBB", body)
            assert depth == 8 and colour in (2, 6) and interlace == 0, "unexpected PNG format"
        elif kind == b"IDAT":
            idat += body
        pos += 12 + n
    bpp = 3 if colour == 2 else 4
    raw, stride = zlib.decompress(idat), width * bpp
    rows, prev = [], bytearray(stride)
    for y in range(height):
        f = raw[y * (stride + 1)]
        line = bytearray(raw[y * (stride + 1) + 1:(y + 1) * (stride + 1)])
        for i in range(stride):
            a = line[i - bpp] if i >= bpp else 0
            b, c = prev[i], prev[i - bpp] if i >= bpp else 0
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
        rows.append(line)
        prev = line
    return [tuple(row[x * bpp:x * bpp + 3]) for row in rows for x in range(width)]


def check_drawn(png, what):
    """The canvas shows more than its background: other colours on a fair share of it."""
    pixels = png_pixels(png)
    counts = {}
    for p in pixels:
        counts[p] = counts.get(p, 0) + 1
    background = max(counts, key=counts.get)
    drawn = sum(1 for p in pixels if max(abs(p[k] - background[k]) for k in range(3)) > 8)
    check(len(counts) > 1, "%s: the canvas is one colour" % what)
    check(drawn > 0.02 * len(pixels), "%s: only %d of %d canvas pixels differ from the background" % (what, drawn, len(pixels)))
    return len(counts), drawn / max(len(pixels), 1)


def at_path(report, path):
    value = report
    for key in path.split("."):
        value = value[int(key)] if isinstance(value, list) else value[key]
    return value


def check_numbers(devtools, report, what, required):
    items = devtools.evaluate("Array.from(document.querySelectorAll('[data-key]'))"
                              ".map(e => [e.dataset.key, e.dataset.value, e.textContent])")
    keys = set()
    for key, value, text in items:
        keys.add(key)
        try:
            expected = at_path(report, key)
        except (KeyError, IndexError, ValueError):
            check(False, "%s: the page shows %s, which the JSON report does not have" % (what, key))
            continue
        check(json.loads(value) == expected, "%s: %s is %s on the page, %r in the report" % (what, key, value, expected))
        # The text shown says the same, to its printed precision.
        if isinstance(expected, (int, float)) and not isinstance(expected, bool):
            shown = text.replace(",", "").replace("%", "").replace(" s", "").strip()
            try:
                number = float(shown)
                check(abs(number - expected) <= 1e-3 * abs(expected) + 1e-12,
                      "%s: %s reads %r on the page, %r in the report" % (what, key, text, expected))
            except ValueError:
                check(False, "%s: %s reads %r on the page, not a number" % (what, key, text))
        elif isinstance(expected, bool):
            check(text == ("yes" if expected else "no"), "%s: %s reads %r, the report says %r" % (what, key, text, expected))
    for key in required:
        check(key in keys, "%s: the page does not show %s" % (what, key))
    return len(items)


def run(cmd, **kw):
    start = time.time()
    r = subprocess.run(cmd, capture_output=True, text=True, **kw)
    return r, time.time() - start


def holed_cube_obj(path, n=10, hole=(4, 4)):
    """The unit cube's six faces as n x n quads each, one quad of the top face left out: a hole
    1/n wide that lets a seed point's volume out."""
    points, index, faces = [], {}, []

    def vid(p):
        key = tuple(round(c * n) for c in p)
        if key not in index:
            index[key] = len(points) + 1
            points.append(p)
        return index[key]

    for axis in range(3):
        for side in (0, 1):
            for i in range(n):
                for j in range(n):
                    if axis == 2 and side == 1 and (i, j) == hole:
                        continue
                    quad = []
                    for di, dj in ((0, 0), (1, 0), (1, 1), (0, 1)):
                        p = [0.0, 0.0, 0.0]
                        p[axis] = float(side)
                        p[(axis + 1) % 3], p[(axis + 2) % 3] = (i + di) / n, (j + dj) / n
                        quad.append(vid(p))
                    if side == 0:
                        quad.reverse()
                    faces += [(quad[0], quad[1], quad[2]), (quad[0], quad[2], quad[3])]
    with open(path, "w") as f:
        f.writelines("v %r %r %r\n" % tuple(p) for p in points)
        f.writelines("f %d %d %d\n" % t for t in faces)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--cli", required=True)
    ap.add_argument("--data", required=True)
    ap.add_argument("--work", required=True)
    ap.add_argument("--model", default="fandisk.obj")
    ap.add_argument("--screenshot", help="also keep a screenshot of the whole page here")
    args = ap.parse_args()
    chromium = next((shutil.which(c) for c in ("chromium", "chromium-browser", "google-chrome") if shutil.which(c)), None)
    if not chromium:
        print("SKIP: Chromium is not installed (scripts/install-deps.sh installs the chromium package)")
        return 77
    os.makedirs(args.work, exist_ok=True)
    work = tempfile.mkdtemp(prefix="html-report-", dir=args.work)
    model = os.path.join(args.data, args.model)
    page, report_path, out = (os.path.join(work, n) for n in ("report.html", "report.json", "wrap.obj"))

    # No three.js: exit code 2 before the work, nothing written.
    env = dict(os.environ, VDBWRAP_THREE_JS=os.path.join(work, "missing", "three.min.js"))
    r, seconds = run([args.cli, "wrap", model, "-o", out, "--html", page, "-q"], env=env)
    check(r.returncode == 2, "missing three.js: exit code %d, not 2 (%s)" % (r.returncode, r.stderr.strip()))
    check("three" in r.stderr, "missing three.js: the message does not name it: " + r.stderr.strip())
    check(not os.path.exists(out) and not os.path.exists(page), "missing three.js: files were written")
    # --html into a folder that does not exist: exit code 2, like -o.
    r, _ = run([args.cli, "wrap", model, "-o", out, "--html", os.path.join(work, "nowhere", "r.html"), "-q"])
    check(r.returncode == 2 and "--html" in r.stderr, "--html in a missing folder: exit %d, %s" % (r.returncode, r.stderr.strip()))

    r, seconds = run([args.cli, "wrap", model, "-o", out, "--report", report_path, "--html", page])
    if not check(r.returncode == 0, "wrap --html: exit code %d: %s" % (r.returncode, r.stderr[-2000:])):
        return 1
    print("%s: page %.2f MB; %s" % (args.model, os.path.getsize(page) / 1e6,
                                     [l for l in r.stderr.splitlines() if "page " in l]))
    report = json.load(open(report_path))

    # The leak: a seed point inside a cube with a hole.
    holed = os.path.join(work, "holed_cube.obj")
    holed_cube_obj(holed)
    leak_page, leak_report = os.path.join(work, "leak.html"), os.path.join(work, "leak.json")
    r, _ = run([args.cli, "wrap", holed, "-o", os.path.join(work, "leak.obj"), "--volume", "0.5,0.5,0.5",
                "--report", leak_report, "--html", leak_page, "-q"])
    check(r.returncode == 4, "leak: exit code %d, not 4: %s" % (r.returncode, r.stderr.strip()))
    check(os.path.exists(leak_page), "leak: no page written")

    # Parts: two STL solids.
    parts_page, parts_report = os.path.join(work, "parts.html"), os.path.join(work, "parts.json")
    r, _ = run([args.cli, "wrap", os.path.join(args.data, "multibody.stl"), "-o", os.path.join(work, "parts.obj"),
                "--report", parts_report, "--html", parts_page, "-q"])
    check(r.returncode == 0, "multibody.stl: exit code %d: %s" % (r.returncode, r.stderr.strip()))

    devtools = DevTools(chromium, work)
    try:
        state = devtools.load(page)
        message = devtools.evaluate("document.getElementById('message').textContent")
        check(state == "ready", "%s: the viewer ended '%s' (%s)" % (args.model, state, message))
        colours, share = check_drawn(devtools.screenshot("#canvas", 0.5), args.model)
        print("%s: canvas %d colours, %.0f%% drawn" % (args.model, colours, 100 * share))
        shown = check_numbers(devtools, report, args.model,
                              ["input.triangles", "output.triangles", "output.valid_closed_surface",
                               "distance_output_to_input.max_percent_of_diagonal", "parameters.base_size",
                               "stages.0.seconds", "total_seconds"])
        print("%s: %d numbers on the page match the JSON report" % (args.model, shown))
        # The wrap's deviation field: offered, and its largest vertex distance within the report's
        # sampled wrap-to-input maximum (the samples include every vertex).
        check(devtools.evaluate("!document.querySelector('[data-colour=deviation]').disabled"),
              "%s: no deviation colouring" % args.model)
        devtools.evaluate("document.querySelector('[data-colour=deviation]').click()")
        deviation_max = float(devtools.evaluate("document.querySelector('[data-deviation-max]').dataset.deviationMax"))
        sampled_max = report["distance_output_to_input"]["max"]
        check(0 < deviation_max <= sampled_max * (1 + 1e-9),
              "%s: largest deviation %r, the report's sampled maximum %r" % (args.model, deviation_max, sampled_max))
        if args.screenshot:
            with open(args.screenshot, "wb") as f:
                f.write(devtools.screenshot())
        # Every view and colouring draws without an error.
        for button in ("[data-show=input]", "[data-show=both]", "[data-colour=defect]", "[data-colour=part]",
                       "[data-colour=deviation]", "#toggle-features", "#toggle-edges", "[data-show=wrap]"):
            enabled = devtools.evaluate("(() => { const b = document.querySelector('%s');"
                                        " if (!b || b.disabled) return false; b.click(); return true; })()" % button)
            if enabled:
                devtools.evaluate("new Promise(r => requestAnimationFrame(() => requestAnimationFrame(r)))")
                check_drawn(devtools.screenshot("#canvas", 0.25), "%s after %s" % (args.model, button))
        for e in devtools.errors():
            check(False, "%s: %s" % (args.model, e))

        state = devtools.load(parts_page)
        check(state == "ready", "multibody.stl: the viewer ended '%s'" % state)
        names = [p["name"] for p in json.load(open(parts_report))["source"]["parts"]]
        clicked = devtools.evaluate("(() => { const b = document.querySelector('[data-colour=part]');"
                                    " if (b.disabled) return false; b.click(); return true; })()")
        check(clicked, "multibody.stl: no colouring by part")
        devtools.evaluate("new Promise(r => requestAnimationFrame(() => requestAnimationFrame(r)))")
        legend = devtools.evaluate("document.getElementById('legend').textContent")
        check(len(names) == 2 and all(n in legend for n in names), "multibody.stl: legend %r, parts %r" % (legend, names))
        check_drawn(devtools.screenshot("#canvas", 0.5), "multibody.stl by part")
        for e in devtools.errors():
            check(False, "multibody.stl: %s" % e)

        state = devtools.load(leak_page)
        check(state == "ready", "leak: the viewer ended '%s'" % state)
        check_drawn(devtools.screenshot("#canvas", 0.5), "leak")
        leak = json.load(open(leak_report))
        check(leak["leak"]["detected"], "leak: the report has no leak")
        check_numbers(devtools, leak, "leak", ["leak.location", "leak.width", "leak.description", "input.triangles"])
        check(devtools.evaluate("!!document.getElementById('toggle-leak') && document.getElementById('toggle-leak').checked"),
              "leak: no leak path shown")
        check(devtools.evaluate("document.querySelector('[data-show=wrap]').disabled"), "leak: a wrap is offered")
        for e in devtools.errors():
            check(False, "leak: %s" % e)
    finally:
        devtools.close()
    if FAILURES:
        print("%d failure(s)" % len(FAILURES), file=sys.stderr)
        return 1
    shutil.rmtree(work, ignore_errors=True)
    print("ok")
    return 0


if __name__ == "__main__":
    sys.exit(main())
