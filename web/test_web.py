#!/usr/bin/env python3
"""The web studio in a real browser: Debian's headless Chromium driven through ChromeDriver
(the W3C WebDriver protocol, spoken with the standard library), against target/web/ served on
127.0.0.1. It does what a user does: loads the page, waits for the first frame, rotates a joint
and grabs a cage vertex with the pointer and the keys, undoes, opens data/fox/Fox.glb through the
file input, binds it again with automatic weights (computed in the page's worker), downloads a
session, and opens bad files. It reads the rig back through the page's
test hook (window.cagerigTest), compares it with `cagerig edit` on the same script to round-off,
times the engine in the page, and writes screenshots and report.json to the output folder.

usage: web/test_web.py [--site target/web] [--cli target/debug/cagerig] [--out target/web-test]
"""

import argparse
import base64
import functools
import http.server
import json
import math
import os
import shutil
import socket
import statistics
import subprocess
import sys
import tempfile
import threading
import time
import urllib.error
import urllib.request
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


def free_port():
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


class Quiet(http.server.SimpleHTTPRequestHandler):
    def log_message(self, *args):
        pass


class WebDriver:
    """The few WebDriver commands the test needs."""

    def __init__(self, driver_port, download_dir):
        self.base = f"http://127.0.0.1:{driver_port}"
        flags = [
            "--headless=new", "--no-sandbox", "--disable-dev-shm-usage", "--no-first-run",
            "--disable-background-networking", "--disable-component-update", "--disable-sync",
            "--disable-quic", "--window-size=1600,900", "--use-angle=swiftshader",
            "--enable-unsafe-swiftshader", f"--user-data-dir={tempfile.mkdtemp(prefix='cagerig-chrome-')}",
        ]
        caps = {"capabilities": {"alwaysMatch": {
            "browserName": "chrome",
            "goog:chromeOptions": {
                "binary": "/usr/bin/chromium", "args": flags,
                "prefs": {"download.default_directory": str(download_dir),
                          "download.prompt_for_download": False,
                          # A download asked for by the test hook has no user gesture behind it.
                          "profile.default_content_setting_values.automatic_downloads": 1},
            },
            "goog:loggingPrefs": {"browser": "ALL"},
        }}}
        self.session = self.call("POST", "/session", caps)["sessionId"]

    def call(self, method, path, body=None, timeout=300):
        data = None if body is None else json.dumps(body).encode()
        request = urllib.request.Request(self.base + path, data=data, method=method,
                                         headers={"Content-Type": "application/json"})
        try:
            with urllib.request.urlopen(request, timeout=timeout) as response:
                return json.loads(response.read())["value"]
        except urllib.error.HTTPError as e:
            raise RuntimeError(f"WebDriver {method} {path}: {e.read().decode()[:2000]}") from None

    def s(self, method, path, body=None, timeout=300):
        return self.call(method, f"/session/{self.session}{path}", body, timeout)

    def get(self, url):
        self.s("POST", "/url", {"url": url})

    def js(self, script, *args):
        return self.s("POST", "/execute/sync", {"script": script, "args": list(args)})

    def js_async(self, script, *args):
        return self.s("POST", "/execute/async", {"script": script, "args": list(args)})

    def actions(self, *sources):
        self.s("POST", "/actions", {"actions": list(sources)})
        self.s("DELETE", "/actions")

    def click_at(self, x, y):
        self.actions({"type": "pointer", "id": "mouse", "parameters": {"pointerType": "mouse"},
                      "actions": [{"type": "pointerMove", "x": int(x), "y": int(y), "duration": 50},
                                  {"type": "pause", "duration": 100},
                                  {"type": "pointerDown", "button": 0},
                                  {"type": "pause", "duration": 80},
                                  {"type": "pointerUp", "button": 0},
                                  {"type": "pause", "duration": 150}]})

    def move_to(self, x, y):
        self.actions({"type": "pointer", "id": "mouse", "parameters": {"pointerType": "mouse"},
                      "actions": [{"type": "pointerMove", "x": int(x), "y": int(y), "duration": 200},
                                  {"type": "pause", "duration": 150}]})

    def keys(self, *keys, modifier=None):
        down = ([{"type": "keyDown", "value": modifier}] if modifier else [])
        seq = down[:]
        for k in keys:
            seq += [{"type": "keyDown", "value": k}, {"type": "pause", "duration": 60},
                    {"type": "keyUp", "value": k}, {"type": "pause", "duration": 60}]
        if modifier:
            seq.append({"type": "keyUp", "value": modifier})
        seq.append({"type": "pause", "duration": 200})
        self.actions({"type": "key", "id": "keyboard", "actions": seq})

    def screenshot(self, path):
        path.write_bytes(base64.b64decode(self.s("GET", "/screenshot")))

    def browser_log(self):
        try:
            return self.s("POST", "/se/log", {"type": "browser"})
        except RuntimeError:
            return []

    def quit(self):
        try:
            self.s("DELETE", "")
        except Exception:
            pass


def wait(what, check, timeout=120.0, step=0.1):
    end = time.monotonic() + timeout
    while True:
        value = check()
        if value:
            return value
        if time.monotonic() > end:
            raise AssertionError(f"timed out after {timeout:.0f} s waiting for {what}")
        time.sleep(step)


def without_skin(glb):
    """A .glb's bytes with its skins, animations and the vertex attributes that bind a mesh to
    a skeleton removed (the JSON chunk rewritten, the binary chunk kept)."""
    import struct
    length, = struct.unpack_from("<I", glb, 12)
    doc = json.loads(glb[20:20 + length])
    doc.pop("skins", None)
    doc.pop("animations", None)
    for node in doc.get("nodes", []):
        node.pop("skin", None)
    for mesh in doc.get("meshes", []):
        for primitive in mesh["primitives"]:
            for attribute in ("JOINTS_0", "WEIGHTS_0"):
                primitive["attributes"].pop(attribute, None)
    text = json.dumps(doc).encode()
    text += b" " * (-len(text) % 4)
    rest = glb[20 + length:]
    total = 12 + 8 + len(text) + len(rest)
    return struct.pack("<III", 0x46546C67, 2, total) + struct.pack("<II", len(text), 0x4E4F534A) + text + rest


def drop_file(driver, target, name, data):
    """Drags a file called `name` holding `data` onto `target` (a JS expression: `window`, or an
    element, whose centre it is dropped on) as a user's drop does: dragenter, dragover, drop."""
    driver.js_async("const done = arguments[arguments.length - 1];"
                    "const transfer = new DataTransfer();"
                    "transfer.items.add(new File([new Uint8Array(arguments[0])], arguments[1]));"
                    f"const target = {target};"
                    "const rect = target.getBoundingClientRect ? target.getBoundingClientRect()"
                    "                                          : {left: 0, top: 0, width: 0, height: 0};"
                    "const at = {clientX: rect.left + rect.width / 2, clientY: rect.top + rect.height / 2};"
                    "for (const type of ['dragenter', 'dragover', 'drop']) {"
                    "  target.dispatchEvent(new DragEvent(type, {dataTransfer: transfer, bubbles: true,"
                    "                                            cancelable: true, ...at}));"
                    "}"
                    "done();", list(data), name)


def obj_vertices(path):
    return [[float(x) for x in line.split()[1:4]] for line in path.read_text().splitlines()
            if line.startswith("v ")]


def max_difference(a, b):
    assert len(a) == len(b), f"{len(a)} points against {len(b)}"
    return max((abs(x - y) for p, q in zip(a, b) for x, y in zip(p, q)), default=0.0)


def diagonal(points):
    lo = [min(p[i] for p in points) for i in range(3)]
    hi = [max(p[i] for p in points) for i in range(3)]
    return math.dist(lo, hi)


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--site", type=Path, default=ROOT / "target/web")
    parser.add_argument("--cli", type=Path, default=ROOT / "target/release/cagerig")
    parser.add_argument("--out", type=Path, default=ROOT / "target/web-test")
    parser.add_argument("--chromedriver", default="/usr/bin/chromedriver")
    args = parser.parse_args()
    site, out = args.site.resolve(), args.out.resolve()
    assert (site / "index.html").is_file(), f"{site}: no index.html (run web/build.sh first)"
    assert args.cli.is_file(), f"{args.cli}: no cagerig command (cargo build --release -p cagerig-cli)"
    shutil.rmtree(out, ignore_errors=True)
    downloads = out / "downloads"
    downloads.mkdir(parents=True)
    report = {"checks": []}

    def check(name, ok, detail=""):
        report["checks"].append({"check": name, "ok": bool(ok), "detail": detail})
        print(("ok   " if ok else "FAIL ") + name + (f": {detail}" if detail else ""), flush=True)
        if not ok:
            raise AssertionError(f"{name}: {detail}")

    handler = functools.partial(Quiet, directory=str(site))
    server = http.server.ThreadingHTTPServer(("127.0.0.1", free_port()), handler)
    threading.Thread(target=server.serve_forever, daemon=True).start()
    url = f"http://127.0.0.1:{server.server_address[1]}/index.html"
    driver_port = free_port()
    chromedriver = subprocess.Popen([args.chromedriver, f"--port={driver_port}"],
                                    stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    driver = None
    try:
        wait("chromedriver", lambda: socket.socket().connect_ex(("127.0.0.1", driver_port)) == 0, 30)
        driver = WebDriver(driver_port, downloads)
        status = lambda: driver.js("return window.cagerigTest && window.cagerigTest.ready ? cagerigTest.status() : null")
        state = lambda: driver.js("return cagerigTest.rigState()")

        def settle(frames=2):
            """Waits until the page has drawn `frames` more frames (its events are handled
            once per frame, and a software-rendered frame takes up to a second)."""
            start = status()["frames"]
            wait("frames", lambda: status()["frames"] >= start + frames, 60, 0.05)

        # 1. The page loads and draws the built-in snake.
        started = time.monotonic()
        driver.get(url)
        first = wait("the first frames", lambda: (s := status()) and s["frames"] >= 3 and s)
        load_s = time.monotonic() - started
        check("the page starts on the built-in snake", first["name"].startswith("builtin:snake"),
              f"{first['name']}, {first['vertices']} vertices, loaded in {load_s:.1f} s")
        report["load_seconds"] = load_s
        driver.screenshot(out / "snake.png")
        rest = state()

        # 2. A joint rotated with the pointer: click it in the current-pose view, R, move, click.
        joint = 3
        x, y = driver.js("return cagerigTest.screenPoint('joint', arguments[0])", joint)
        driver.click_at(x, y)
        # R rotates about the joint by the pointer's angle around it: start beside the joint
        # and turn a quarter.
        driver.move_to(x + 80, y)
        settle()
        driver.keys("r")
        settle()
        driver.move_to(x + 57, y + 57)
        settle()
        driver.move_to(x, y + 80)
        settle()
        driver.click_at(x, y + 80)
        settle()
        rotated = state()
        moved = max_difference(rotated["posed_joints"], rest["posed_joints"])
        check("a joint rotated with the pointer moves the posed skeleton", moved > 1e-3,
              f"largest joint move {moved:.4f}")
        depth_after_rotate = status()["undo_depth"]

        # 3. A current-cage vertex grabbed with the pointer: click it, G, move, click.
        cage_points = [driver.js("return cagerigTest.screenPoint('cage', arguments[0])", k)
                       for k in range(len(rest["posed_cage"]))]
        joint_points = [driver.js("return cagerigTest.screenPoint('joint', arguments[0])", j)
                        for j in range(len(rest["posed_joints"]))]
        width = driver.js("return window.innerWidth")
        # A vertex of the current-pose view, as far as possible from every drawn joint (a
        # click there selects the cage vertex, not a joint).
        left = [(k, p) for k, p in enumerate(cage_points)
                if p and 40 < p[0] < width / 2 - 60 and 100 < p[1] < 500]
        k, (cx, cy) = max(left, key=lambda kp: min(math.dist(kp[1], q) for q in joint_points if q))
        driver.click_at(cx, cy)
        settle()
        driver.keys("g")
        settle()
        driver.move_to(cx + 20, cy - 15)
        settle()
        driver.move_to(cx + 40, cy - 30)
        settle()
        driver.click_at(cx + 40, cy - 30)
        settle()
        grabbed = state()
        driver.screenshot(out / "snake-edited.png")
        grab = math.dist(grabbed["posed_cage"][k], rotated["posed_cage"][k])
        check("a cage vertex grabbed with the pointer moves C'", grab > 1e-3,
              f"C'[{k}] moved {grab:.4f}; undo depth {status()['undo_depth']}")

        # 4. Undo (Ctrl+Z) twice gives the rig back exactly.
        driver.keys("z", modifier="\ue009")
        settle()
        driver.keys("z", modifier="\ue009")
        settle()
        undone = state()
        worst = max(max_difference(undone[key], rest[key]) for key in rest) / diagonal(rest["rest_mesh"])
        check("Ctrl+Z twice restores every structure to round-off",
              worst <= 1e-12 and depth_after_rotate >= 1,
              f"largest difference {worst:.1e} of the diagonal")

        # 5. The same script in the page and in the native library.
        script = (ROOT / "examples/edits.json").read_text()
        driver.js("return cagerigTest.runScript(arguments[0])", script)
        page = state()
        with tempfile.TemporaryDirectory() as native:
            subprocess.run([str(args.cli), "edit", "--builtin", "snake", "--resolution", "4096",
                            "--script", str(ROOT / "examples/edits.json"), "--out", native + "/e"],
                           check=True, capture_output=True)
            steps = len(json.loads(script)["steps"])
            last = Path(native) / "e"
            native_state = {
                "posed_mesh": obj_vertices(last / f"step{steps}_mesh_posed.obj"),
                "rest_mesh": obj_vertices(last / f"step{steps}_mesh_rest.obj"),
                "posed_cage": obj_vertices(last / f"step{steps}_cage_posed.obj"),
                "rest_cage": obj_vertices(last / f"step{steps}_cage_rest.obj"),
                "posed_joints": [j["posed"] for j in json.loads((last / f"step{steps}_joints.json").read_text())],
            }
        scale = diagonal(native_state["rest_mesh"])
        differences = {key: max_difference(page[key], native_state[key]) / scale for key in native_state}
        report["native_difference_over_diagonal"] = differences
        check("the page's rig equals the native library's on examples/edits.json",
              max(differences.values()) <= 1e-9,
              ", ".join(f"{k} {v:.1e}" for k, v in differences.items()))

        # 6. Engine time per event in the page (performance.now() around the engine's calls).
        def time_events(name, steps, repeats=7):
            times = {}
            for label, step in steps.items():
                steps = step if isinstance(step, list) else [step]
                samples = [driver.js("return cagerigTest.runScript(arguments[0])",
                                     json.dumps({"steps": steps})) for _ in range(repeats)]
                times[label] = statistics.median(samples)
                report.setdefault("event_samples_ms", {}).setdefault(name, {})[label] = samples
            report.setdefault("event_ms", {})[name] = times
            print(f"     {name}: " + ", ".join(f"{k} {v:.2f} ms" for k, v in times.items()), flush=True)
            return times

        snake_events = {
            "rotate joint": {"op": "rotate_joint", "joint": 3, "axis": [1, 0, 0], "degrees": 2},
            "drag rest cage": {"op": "move_rest_cage", "vertices": [0, 2, 4], "offset": [0.002, 0, 0]},
            "grab current cage": {"op": "move_posed_cage", "vertices": [10], "offset": [0, 0.002, 0]},
            # The first grab after a pose change factorises CageRev (Eq. 19) for the new pose.
            "rotate a joint, then grab": [
                {"op": "rotate_joint", "joint": 3, "axis": [1, 0, 0], "degrees": 2},
                {"op": "move_posed_cage", "vertices": [10], "offset": [0, 0.002, 0]},
            ],
        }
        time_events("snake", snake_events)

        # 7. Ctrl+S downloads the session (the edits are then saved: the next open asks nothing).
        def download_session(name):
            before = set(downloads.glob("*.cagerig"))
            driver.keys("s", modifier="\ue009")
            saved = wait(f"the download of {name}", lambda: [p for p in downloads.glob("*.cagerig")
                                                            if p not in before and p.stat().st_size], 30)
            session = json.loads(saved[0].read_text())
            check(f"Ctrl+S downloads the session of {name}", not status()["unsaved"],
                  f"{saved[0].name}: {saved[0].stat().st_size} bytes, source {session['source']}")
            return session

        download_session("the snake")

        # 8. The Fox through the file input.
        fox = ROOT / "data/fox/Fox.glb"
        element = driver.s("POST", "/element", {"using": "css selector", "value": "#file"})
        element_id = next(iter(element.values()))
        driver.s("POST", f"/element/{element_id}/value", {"text": str(fox)})
        opened = wait("the Fox to open", lambda: (s := status()) and s["name"] == "Fox.glb" and not s["opening"] and s, 120)
        check("data/fox/Fox.glb opens through the file input",
              opened["joints"] and opened["cage_vertices"],
              f"{opened['vertices']} vertices, {opened['joints']} joints, {opened['cage_vertices']} cage vertices")
        # The Fox has no cage: the worker generated it while the page went on (its 20 ms timer
        # kept firing), then the page's thread bound the rig.
        worker = driver.js("return cagerigTest.lastWorker")
        fox_lines = [l["text"] for l in status()["log"] if l["text"].startswith("opened Fox.glb")]
        fox_bind_ms = float(fox_lines[-1].rsplit("(", 1)[1].split(" ms")[0])
        report["fox_open"] = {"worker_ms": worker["ms"], "page_longest_pause_ms": worker["longestGapMs"],
                              "page_bind_ms": fox_bind_ms}
        check("the Fox's cage is generated in the worker while the page stays responsive",
              worker["ms"] > 0 and worker["longestGapMs"] < max(250.0, 0.25 * worker["ms"]),
              f"worker {worker['ms']:.0f} ms, the page's longest pause meanwhile {worker['longestGapMs']:.0f} ms, "
              f"then binding on the page's thread {fox_bind_ms:.0f} ms")
        time_events("Fox", {
            "rotate joint": {"op": "rotate_joint", "joint": 5, "axis": [0, 0, 1], "degrees": 2},
            "drag rest cage": {"op": "move_rest_cage", "vertices": [0, 1], "offset": [0.5, 0, 0]},
            "grab current cage": {"op": "move_posed_cage", "vertices": [2], "offset": [0, 0.5, 0]},
            "rotate a joint, then grab": [
                {"op": "rotate_joint", "joint": 5, "axis": [0, 0, 1], "degrees": 2},
                {"op": "move_posed_cage", "vertices": [2], "offset": [0, 0.5, 0]},
            ],
        })
        time.sleep(0.5)
        driver.screenshot(out / "fox.png")

        # 8b. Bind with automatic weights (the Skeleton panel's Bind, re-weighting the Fox): the
        # weights are computed in the worker while the page's 20 ms timer keeps firing, the rig
        # is then bound on the page's thread, and Ω equals the native library's on the same
        # input.
        bound_before = sum(1 for l in status()["log"] if l["text"].startswith("bound "))
        driver.js("cagerigTest.bindAutomatic()")
        binding_seen = status()["binding"]
        bound = wait("the bind with automatic weights", lambda: (s := status()) and not s["binding"] and
                     sum(1 for l in s["log"] if l["text"].startswith(("bound ", "bind:"))) > bound_before and s, 120)
        line = [l["text"] for l in bound["log"] if l["text"].startswith(("bound ", "bind:"))][-1]
        weights_run = driver.js("return cagerigTest.lastWeights")
        page_weights = driver.js("return cagerigTest.skinWeights()")
        # The native library on what the page gave its worker: the rest mesh, the cage and the
        # skeleton as OBJ and .skt files for `cagerig weights` (same default options).
        given = json.loads(weights_run["input"])
        with tempfile.TemporaryDirectory() as native:
            def write_obj(path, mesh):
                path.write_text("".join(f"v {x!r} {y!r} {z!r}\n" for x, y, z in mesh["positions"]) +
                                "".join(f"f {a + 1} {b + 1} {c + 1}\n" for a, b, c in mesh["triangles"]))
            write_obj(Path(native) / "mesh.obj", given["mesh"])
            write_obj(Path(native) / "cage.obj", given["cage"])
            (Path(native) / "skeleton.skt").write_text("".join(
                f"j {j} {joint['name']} {-1 if joint['parent'] is None else joint['parent']} "
                + " ".join(repr(x) for x in joint["rest_world_from_joint"][-3:]) + "\n"
                for j, joint in enumerate(given["joints"])))
            subprocess.run([str(args.cli), "weights", native + "/mesh.obj", "--skeleton", native + "/skeleton.skt",
                            "--cage", native + "/cage.obj", "--out", native + "/w.skw"],
                           check=True, capture_output=True)
            native_rows = [{} for _ in page_weights["rows"]]
            for row in (Path(native) / "w.skw").read_text().splitlines():
                fields = row.split()
                if len(fields) == 3 and not row.startswith("#"):
                    native_rows[int(fields[1])][int(fields[0])] = float(fields[2])
        def row_difference(page_row, native_row):
            page_row = {j: w for j, w in page_row}
            return max((abs(page_row.get(j, 0.0) - native_row.get(j, 0.0))
                        for j in set(page_row) | set(native_row)), default=0.0)
        weights_difference = max(row_difference(p, n) for p, n in zip(page_weights["rows"], native_rows))
        report["fox_bind"] = {"worker_ms": weights_run["ms"], "page_longest_pause_ms": weights_run["longestGapMs"],
                              "line": line, "weights_difference": weights_difference}
        check("Bind with automatic weights computes them in the worker while the page stays responsive",
              line.startswith("bound 24 joints") and binding_seen and weights_run["ms"] > 0
              and weights_run["longestGapMs"] < max(250.0, 0.25 * weights_run["ms"]),
              f"worker {weights_run['ms']:.0f} ms, the page's longest pause meanwhile "
              f"{weights_run['longestGapMs']:.0f} ms; {line}")
        check("the automatic weights bound in the page equal the native library's",
              weights_difference <= 1e-9, f"largest difference {weights_difference:.1e}")

        session = download_session("the Fox")
        check("the Fox's session names its file", session["source"].get("path") == "Fox.glb",
              json.dumps(session["source"]))

        # 9. File ▸ Download glTF: a .glb the native library reads back.
        driver.js("cagerigTest.downloadGlb()")
        glb = wait("the .glb download", lambda: [p for p in downloads.glob("*.glb") if p.stat().st_size], 30)[0]
        info = subprocess.run([str(args.cli), "info", str(glb)], capture_output=True, text=True)
        check("the downloaded .glb opens in the native library", info.returncode == 0 and "24 joints" in info.stdout,
              f"{glb.name}: {glb.stat().st_size} bytes; {info.stderr.strip()[:200]}")

        # 9b. A skinless character dropped on the page: the Fox with its skin, skeleton and
        # animations taken out. It opens as a mesh to rig, in a cage the worker generated.
        skinless = without_skin(fox.read_bytes())
        drop_file(driver, "window", "skinless-fox.glb", skinless)
        dropped = wait("the dropped skinless Fox to open",
                       lambda: (s := status()) and s["name"] == "skinless-fox.glb" and not s["opening"] and s, 120)
        notes = [l["text"] for l in dropped["log"]]
        opened_line = [n for n in notes if n.startswith("opened skinless-fox.glb")][-1]
        check("a skinless .glb dropped on the page opens as a mesh to rig, in a generated cage",
              " 0 joints" in opened_line and dropped["cage_vertices"] > 0
              and any("no skeleton: build one" in n for n in notes)
              and any("generated one" in n for n in notes),
              f"{opened_line}; {[n for n in notes if 'skeleton' in n][-1:]}")

        # 9c. A character dropped on the studio's canvas: egui reads it (eframe's drop handler,
        # which keeps the event from the page's own handler) and hands its bytes to the page
        # (PageFiles::open_dropped), which opens it through the worker. It opens once.
        cesium_man = (ROOT / "data/gltf/CesiumMan/CesiumMan.glb").read_bytes()
        drop_file(driver, "document.getElementById('studio')", "canvas-dropped.glb", cesium_man)
        dropped = wait("the character dropped on the canvas to open",
                       lambda: (s := status()) and s["name"] == "canvas-dropped.glb" and not s["opening"] and s, 120)
        time.sleep(1.0)
        opened = [l["text"] for l in status()["log"] if l["text"].startswith("opened canvas-dropped.glb")]
        check("a .glb dropped on the studio's canvas opens once, read by the studio",
              len(opened) == 1 and " 19 joints" in opened[0] and dropped["cage_vertices"] > 0,
              f"{opened}")

        # 10. The Arm sample (its cage is in the file): the binding's time on the page's thread.
        driver.js("window.cagerigPage.fetchSample('Arm.glb')")
        wait("the Arm to open", lambda: (s := status()) and s["name"] == "Arm.glb" and not s["opening"], 120)
        lines = [l["text"] for l in status()["log"] if l["text"].startswith("opened Arm.glb")]
        arm_ms = float(lines[-1].rsplit("(", 1)[1].split(" ms")[0])
        report["arm_open_ms"] = arm_ms
        print(f"     Arm: opened and bound in {arm_ms:.0f} ms", flush=True)

        # 11. Bad files give a message, and the page goes on.
        truncated = list(fox.read_bytes()[:4000])
        for name, payload in [("truncated.glb", truncated),
                              ("no-mesh.gltf", list(b'{"asset":{"version":"2.0"},"scenes":[{"nodes":[]}]}')),
                              ("big.glb", 50 * 1048576)]:
            errors_before = sum(1 for l in status()["log"] if l["level"] == "Error")
            # A list is the file's bytes; a number, the size of a file of zeros.
            driver.js_async("const done = arguments[arguments.length - 1];"
                            "const bytes = typeof arguments[1] === 'number' ? new ArrayBuffer(arguments[1])"
                            " : new Uint8Array(arguments[1]).buffer;"
                            "cagerigTest.openFile(arguments[0], bytes).then(done)",
                            name, payload)
            after = wait(f"{name} to be refused", lambda: (s := status()) and not s["opening"] and
                         sum(1 for l in s["log"] if l["level"] == "Error") > errors_before and s, 60)
            message = [l["text"] for l in after["log"] if l["level"] == "Error"][-1]
            check(f"{name} is refused with a message, and the Arm stays open",
                  name in message and after["name"] == "Arm.glb", message[:160])
        driver.screenshot(out / "bad-file.png")

        # 12. No errors in the console.
        console = [e for e in driver.browser_log() if e.get("level") == "SEVERE"]
        check("the console has no errors", not console, json.dumps(console)[:1000])
    finally:
        (out / "report.json").write_text(json.dumps(report, indent=1))
        if driver:
            driver.quit()
        chromedriver.terminate()
        server.shutdown()
    print(f"web test passed: {len(report['checks'])} checks; screenshots and report.json in {out}")


if __name__ == "__main__":
    sys.exit(main())
