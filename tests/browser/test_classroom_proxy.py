"""Rigs behind a reverse proxy (docs/scaling.md): nginx routes ``/rig/N/`` to rig N's port,
page and websocket alike, and the instructor token in the URL still reaches the page. The
nginx configuration is the one docs/scaling.md shows, with this test's ports. Skipped where
nginx is not installed (Debian: ``apt-get install nginx-light``)."""

from __future__ import annotations

import shutil
import socket
import subprocess
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest
from helpers import VIEWPORT, close_webgl_toast, free_port, wait_for_text, wait_until

from app.classroom.roles import Access
from app.rig_config import DEFAULT_RIG, build_rig, load_rig_spec
from app.ui.panels.classroom_rig import ServedRig, serve_rig

pytestmark = pytest.mark.browser
LOADED_S = 60.0  # a page on a machine loaded by other test runs can take long to come up
NGINX = shutil.which("nginx") or "/usr/sbin/nginx"

# docs/scaling.md "nginx": the map lists rig number -> host:port (generated from the
# assignment of rigs to machines); here two rigs on this machine.
SITE = """
map $http_upgrade $connection_upgrade { default upgrade; '' close; }
map $rig $rig_backend { default ""; %(map)s }
server {
  listen 127.0.0.1:%(port)d;
  location ~ ^/rig/(?<rig>[0-9]+)/?$ {
    if ($rig_backend = "") { return 404; }
    proxy_pass http://$rig_backend/;
    proxy_http_version 1.1;
    proxy_set_header Upgrade $http_upgrade;
    proxy_set_header Connection $connection_upgrade;
    proxy_set_header Host $host;
    proxy_read_timeout 1h;
    proxy_send_timeout 1h;
    proxy_buffering off;
  }
}
"""


@pytest.fixture
def rigs(tmp_path: Path) -> Iterator[list[ServedRig]]:
    served = [serve_rig(build_rig(load_rig_spec(DEFAULT_RIG), state_dir=tmp_path / f"rig{i}"),
                        Access("tok"), port=free_port(), paused=True) for i in (1, 2)]
    yield served
    for one in served:
        one.stop()


@pytest.fixture
def proxy(tmp_path: Path, rigs: list[ServedRig]) -> Iterator[str]:
    if not Path(NGINX).exists():
        pytest.skip("nginx is not installed")
    port = free_port()
    site = SITE % {"port": port, "map": " ".join(f"{i} 127.0.0.1:{one.port};"
                                                  for i, one in enumerate(rigs, start=1))}
    d = tmp_path
    conf = d / "nginx.conf"
    conf.write_text(
        f"worker_processes 1; pid {d}/nginx.pid; error_log {d}/error.log; events {{}}\n"
        f"http {{ access_log off; client_body_temp_path {d}; proxy_temp_path {d};\n"
        f"fastcgi_temp_path {d}; uwsgi_temp_path {d}; scgi_temp_path {d};\n{site}}}\n")
    proc = subprocess.Popen([NGINX, "-c", str(conf), "-g", "daemon off;"],
                            stderr=subprocess.DEVNULL)
    try:
        # nginx binds its port after it started: a page opened at once was refused once in CI
        deadline = time.monotonic() + 20
        while True:
            try:
                socket.create_connection(("127.0.0.1", port), timeout=1).close()
                break
            except OSError:
                log = d / "error.log"
                assert proc.poll() is None and time.monotonic() < deadline, (
                    f"nginx does not listen on {port}: "
                    f"{log.read_text() if log.exists() else 'no error log'}")
                time.sleep(0.05)
        yield f"http://127.0.0.1:{port}"
    finally:
        proc.terminate()
        proc.wait(timeout=10)


def _open(browser: Any, url: str) -> Any:
    page = browser.new_context(viewport=VIEWPORT, device_scale_factor=1).new_page()
    page.goto(url)
    close_webgl_toast(page, timeout=LOADED_S)
    return page


def test_rig_urls_through_nginx(proxy: str, rigs: list[ServedRig], browser: Any) -> None:
    instructor = _open(browser, f"{proxy}/rig/2/?token=tok&fixedDpr=1")
    trainee = _open(browser, f"{proxy}/rig/1/?fixedDpr=1")
    try:
        wait_for_text(instructor, "You are the instructor", timeout=LOADED_S)
        wait_for_text(trainee, "You are a trainee", timeout=LOADED_S)
        wait_until(lambda: len(rigs[1].server.get_clients()) == 1
                   and len(rigs[0].server.get_clients()) == 1, what="one browser per rig")
        assert rigs[1].classroom.access.role(
            next(iter(rigs[1].server.get_clients()))).value == "instructor"
    finally:
        instructor.context.close()
        trainee.context.close()
