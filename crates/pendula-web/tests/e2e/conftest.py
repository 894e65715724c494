"""`pendula serve` in a real headless Chromium (Debian's, through Playwright's executable_path).

The server is the CLI the Rust tests built (PENDULA_CLI), started on a free loopback port and
stopped by the fixture. Screenshots of each view go to PENDULA_SCREENSHOTS (a temporary
directory unless set: the guide's pictures are taken with it set to docs/web).
"""

import os
import pathlib
import subprocess
import tempfile

import pytest
from playwright.sync_api import sync_playwright

CHROMIUM = "/usr/bin/chromium"
# As the machine's notes say: without the background-networking flags Chromium keeps trying
# hosts this closed network refuses; as root it needs --no-sandbox.
ARGS = ["--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run", "--disable-background-networking",
        "--disable-component-update", "--disable-sync"]


@pytest.fixture(scope="session")
def server():
    cli = os.environ.get("PENDULA_CLI", "target/debug/pendula")
    proc = subprocess.Popen([cli, "serve", "--port", "0"], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    line = proc.stdout.readline()
    url = next((w for w in line.split() if w.startswith("http://")), None)
    if url is None:
        proc.kill()
        raise RuntimeError(f"pendula serve did not print its URL: {line!r} {proc.stderr.read()!r}")
    yield url
    proc.terminate()
    proc.wait(timeout=10)


@pytest.fixture(scope="session")
def browser():
    with sync_playwright() as p:
        b = p.chromium.launch(executable_path=CHROMIUM, headless=True, args=ARGS)
        yield b
        b.close()


@pytest.fixture(scope="session")
def shots():
    where = os.environ.get("PENDULA_SCREENSHOTS")
    path = pathlib.Path(where) if where else pathlib.Path(tempfile.mkdtemp(prefix="pendula-shots-"))
    path.mkdir(parents=True, exist_ok=True)
    return path


def open_lab(browser, url, width=1280, height=900):
    """A page on the lab, connected, with its first config and frames."""
    page = browser.new_page(viewport={"width": width, "height": height})
    errors = []
    page.on("pageerror", lambda e: errors.append(str(e)))
    page.goto(url)
    page.wait_for_function("window.lab && lab.connected && lab.config && lab.framesReceived > 2", timeout=15000)
    page.js_errors = errors
    return page


@pytest.fixture
def lab(browser, server):
    page = open_lab(browser, server)
    yield page
    assert page.js_errors == [], page.js_errors
    page.close()
