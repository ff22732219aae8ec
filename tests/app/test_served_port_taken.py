"""ServedRig's URL is the port its viser server bound. free_port() picks a port, closes it and
hands it to viser, and another process (a parallel test run) can take it in between: viser
then binds the next free port, and the URL, built from the picked port, would lead Chromium
to the other process's dashboard: screenshots and browser tests of the wrong rig."""

from __future__ import annotations

import socket
import urllib.request
from pathlib import Path

import pytest

from app import screenshots
from app.rig_config import DEFAULT_RIG, build_rig, load_rig_spec


def test_url_is_the_port_viser_bound(monkeypatch: pytest.MonkeyPatch,
                                     tmp_path: Path) -> None:
    taken = socket.socket()
    taken.bind(("127.0.0.1", 0))
    taken.listen()
    port = int(taken.getsockname()[1])
    monkeypatch.setattr(screenshots, "free_port", lambda: port)  # lost the race for it
    rig = build_rig(load_rig_spec(DEFAULT_RIG), state_dir=tmp_path)
    served = screenshots.ServedRig.start(rig, quiet=True)
    try:
        assert served.url == f"http://127.0.0.1:{served.server.get_port()}"
        assert served.url != f"http://127.0.0.1:{port}"
        with urllib.request.urlopen(served.url, timeout=10) as answer:
            assert answer.status == 200
    finally:
        served.stop()
        taken.close()
