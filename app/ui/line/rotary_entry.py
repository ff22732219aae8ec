"""The CPX-E-EC's rotary switches typed as seed 002 Tab. 5 writes them, in the Line tab's form.

Tab. 5 sets the Explicit Device ID "в шестнадцатеричной кодировке" with three hex switches,
"0 ... 4095 (1h ... FFFh)", and the Slave tab's Switches row shows them so ("rotary 07B"). The
model's ``set_rotary`` takes the integer; this is only how the form reads what a trainee types:
the hex digits, with or without ``0x`` or a trailing ``h`` ("07B", "7b", "0x07B", "7Bh").
Every digit string is hex, as on the switches: "123" is 0x123, never decimal 123 (a plain
number read as decimal would set another address than the one the manual names). Anything
else is refused before a command goes (docs/cpx-e-ec.md choice 41).
"""

from __future__ import annotations

import re
from collections.abc import Mapping
from dataclasses import replace
from typing import Any

from devices.cpx.actions import ACTIONS
from devices.device import Action, CommandError, Param

ACTION = "set_rotary"
KIND = "cpx_e_ec"  # the rig's kind of the CPX-E-EC (rig.describe())
DIGITS = 3  # Tab. 5: three switches
_HEX = re.compile(r"(?:0[xX])?([0-9A-Fa-f]+)[hH]?")
# The switches' top, from the model's own action table (not a copy of its range).
_HIGH = int(ACTIONS[ACTION].params[0].high or 0)
SPAN = f"{0:0{DIGITS}X} ... {_HIGH:0{DIGITS}X}"


def rotary_from_text(text: Any) -> int:
    """"07B" / "0x07B" / "7Bh" -> 0x7B; CommandError in words for anything the switches
    cannot show."""
    typed = str(text).strip()
    found = _HEX.fullmatch(typed)
    if found is None:
        raise CommandError(f"rotary {typed!r}: three hex digits as the switches show them, "
                           f"{SPAN} (e.g. 07B or 0x07B; seed 002 Tab. 5)")
    value = int(found.group(1), 16)
    if value > _HIGH:
        raise CommandError(f"rotary {typed!r}: 0x{value:X} is above {_HIGH:X}: the three "
                           f"switches read {SPAN} (hex, seed 002 Tab. 5)")
    return value


def _text_param(param: Param) -> Param:
    """The form's box for the switches: text, starting from the snapshot's hex digits."""
    return replace(param, type=str, low=None, high=None, current="switches.rotary_hex",
                   parse=rotary_from_text,
                   doc=f"hex, as the switches: {SPAN} (07B, 0x07B); 000 = the master "
                       "assigns the address")


def form_actions(kind: str, actions: Mapping[str, Action]) -> dict[str, Action]:
    """``actions`` as the slave form offers them: the CPX-E-EC's set_rotary takes hex text."""
    out = dict(actions)
    action = out.get(ACTION)
    if kind == KIND and action is not None:
        out[ACTION] = replace(action, params=tuple(
            _text_param(p) if p.name == "value" else p for p in action.params))
    return out


def model_args(kind: str, name: str, args: dict[str, Any]) -> dict[str, Any]:
    """What the form checked, as the model's command takes it (the hex text as its integer)."""
    if kind == KIND and name == ACTION and isinstance(args.get("value"), str):
        return {**args, "value": rotary_from_text(args["value"])}
    return args
