#!/usr/bin/env python3
"""Opens the dashboard in headless Chromium (through Debian's chromedriver, WebDriver over
HTTP, Python's standard library only), waits until every panel shows data, fails on any
console error, and saves a screenshot.

    browser_check.py URL SCREENSHOT.png [TIMEOUT_SECONDS] [FINISHED_FILE]

With FINISHED_FILE (e.g. a run's result.json), the screenshot waits until that file
exists and the page has polled once more: the run's final state, not its first panels
(scripts/dashboard-screenshot.sh).
"""
import base64
import json
import os
import socket
import subprocess
import sys
import time
import urllib.error
import urllib.request


def free_port():
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


class WebDriver:
    def __init__(self, port):
        self.base = f"http://127.0.0.1:{port}"
        self.session = None

    def call(self, method, path, body=None):
        data = None if body is None else json.dumps(body).encode()
        request = urllib.request.Request(self.base + path, data=data, method=method,
                                         headers={"Content-Type": "application/json"})
        try:
            with urllib.request.urlopen(request, timeout=60) as response:
                return json.loads(response.read() or b"{}").get("value")
        except urllib.error.HTTPError as e:
            raise RuntimeError(f"chromedriver {method} {path}: {e.code} {e.read()[:500]!r}") from None

    def start(self, window):
        caps = {"capabilities": {"alwaysMatch": {
            "browserName": "chrome",
            "goog:chromeOptions": {
                "binary": os.environ.get("HBIRL_CHROMIUM", "/usr/bin/chromium"),
                "args": ["--headless", "--no-sandbox", "--disable-gpu", "--disable-background-networking",
                         "--disable-dev-shm-usage", "--hide-scrollbars", f"--window-size={window}"],
            },
            "goog:loggingPrefs": {"browser": "ALL"},
        }}}
        self.session = self.call("POST", "/session", caps)["sessionId"]

    def s(self, path):
        return f"/session/{self.session}{path}"

    def script(self, source):
        return self.call("POST", self.s("/execute/sync"), {"script": source, "args": []})


PANELS = "return Array.from(document.querySelectorAll('.panel')).map(p => [p.id, p.dataset.state]);"
FRAME = "const i = document.getElementById('frame'); return i.hidden || (i.complete && i.naturalWidth > 0);"


def main():
    url, screenshot = sys.argv[1], sys.argv[2]
    timeout = float(sys.argv[3]) if len(sys.argv) > 3 else 120.0
    finished_file = sys.argv[4] if len(sys.argv) > 4 else None
    port = free_port()
    driver_log = open(screenshot + ".chromedriver.log", "w")
    chromedriver = subprocess.Popen([os.environ.get("HBIRL_CHROMEDRIVER", "/usr/bin/chromedriver"), f"--port={port}"],
                                    stdout=driver_log, stderr=subprocess.STDOUT)
    try:
        wd = WebDriver(port)
        for _ in range(100):
            try:
                wd.call("GET", "/status")
                break
            except (OSError, RuntimeError):
                time.sleep(0.1)
        wd.start("1400,2000")
        wd.call("POST", wd.s("/url"), {"url": url})
        deadline = time.time() + timeout
        panels = []
        while time.time() < deadline:
            panels = wd.script(PANELS)
            if panels and all(state == "filled" for _, state in panels) and wd.script(FRAME):
                break
            time.sleep(0.5)
        else:
            print(f"FAIL: not every panel shows data after {timeout:.0f} s: {panels}", file=sys.stderr)
            return 1
        while finished_file and not os.path.exists(finished_file):
            if time.time() > deadline:
                print(f"FAIL: {finished_file} did not appear within {timeout:.0f} s", file=sys.stderr)
                return 1
            time.sleep(0.5)
        time.sleep(3 if finished_file else 1.5)  # a few more polls: errors in updates would show too
        png = base64.b64decode(wd.call("GET", wd.s("/screenshot")))
        with open(screenshot, "wb") as f:
            f.write(png)
        logs = wd.call("POST", wd.s("/se/log"), {"type": "browser"}) or []
        errors = [e for e in logs if e.get("level") == "SEVERE"]
        for e in logs:
            print(f"console {e.get('level')}: {e.get('message')}", file=sys.stderr)
        wd.call("DELETE", wd.s(""))
        if errors:
            print(f"FAIL: {len(errors)} console errors", file=sys.stderr)
            return 1
        print(f"every panel shows data ({', '.join(p for p, _ in panels)}); no console errors; screenshot {screenshot}")
        return 0
    finally:
        chromedriver.terminate()
        chromedriver.wait(timeout=10)


if __name__ == "__main__":
    sys.exit(main())
