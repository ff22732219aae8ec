"""Write the drive's EDS file: ``python -m app.canopen_eds [--out PATH] [--check]``.

The file is generated from the same definitions the CANopen node serves
(devices/canopen/eds.py), for a drive at its factory settings on CANopen with node-ID 1
(COB-IDs are written relative to ``$NODEID``). ``--check`` exits 1 when the file on disk
differs from what would be written (the test suite runs the same comparison).
"""

from __future__ import annotations

import argparse
import random
import sys
from pathlib import Path

from devices.canopen.eds import eds_text
from devices.canopen.node import CanOpenNode
from devices.flash import MemoryFlash
from devices.servo.drive import DriveConfig, ServoDrive

EDS_PATH = Path(__file__).resolve().parent.parent / "static" / "eds" / "servo_drive.eds"


def generate() -> str:
    drive = ServoDrive("servo", random.Random(0), DriveConfig(node_id=1, fieldbus="canopen"),
                       MemoryFlash())
    return eds_text(CanOpenNode("servo-can", drive).dictionary)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m app.canopen_eds", description=__doc__)
    parser.add_argument("--out", default=str(EDS_PATH), help=f"default: {EDS_PATH}")
    parser.add_argument("--check", action="store_true",
                        help="compare instead of writing; exit 1 when out of date")
    args = parser.parse_args(argv)
    text, out = generate(), Path(args.out)
    if args.check:
        current = out.read_text(encoding="utf-8") if out.exists() else ""
        if current != text:
            print(f"{out} is out of date: run python -m app.canopen_eds", file=sys.stderr)
            return 1
        return 0
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(text, encoding="utf-8")
    print(f"wrote {out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
