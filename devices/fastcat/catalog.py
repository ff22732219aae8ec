"""The 20 FastCAT I/O module types (seed 000 §2) with their channels.

The seed lists the modules but gives no product codes; the codes reported in 0xF050.n are
FieldRig-assigned (0x0000FA01.. in §2 order, see docs/fastcat-modules.md) and must never be
renumbered: stored configurations in flash refer to them.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

GROUPS = ("digital", "analog", "encoder")

# Analog input kinds, converted by devices/fastcat/analog.py; "configurable" = per-channel
# kind chosen by 0x4500 (AI8M, AB4M4).
AI_KIND_NAMES = ("diff_pm10", "current", "thermocouple", "pt100", "pt1000", "pot", "configurable")


@dataclass(frozen=True)
class ModuleType:
    name: str  # exactly as §2 prints it
    description: str  # English rendering of the §2 line
    product_code: int  # FieldRig-assigned, reported in 0xF050.n
    group: str  # "digital" | "analog" | "encoder" (the §2 columns)
    di: int = 0  # digital inputs
    do: int = 0  # digital outputs
    dio: int = 0  # digital channels configurable in groups (DB16)
    dio_group_size: int = 0  # channels per 0x2004 group (DB16: 4 on one connector, §6.6)
    do_current_a: float = 0.5  # rated current per output (DO82: 2 A, §2; others unprinted)
    ai: int = 0  # analog inputs (incl. temperatures and potentiometers)
    ai_kind: str | None = None  # one of AI_KIND_NAMES
    ao: int = 0  # analog outputs
    ao_bits: int = 0  # DAC resolution (AO4 12 bit, AO4H 16 bit, §2)
    encoders: int = 0

    @property
    def counts_as_analog(self) -> bool:
        """Counted for the limit of 8 analog modules (§2); AX2 is in its own §2 column."""
        return self.group == "analog"

    @property
    def configurable_ai(self) -> bool:
        return self.ai_kind == "configurable"

    @property
    def thermocouple(self) -> bool:
        return self.ai_kind == "thermocouple"

    @property
    def temperature(self) -> bool:
        """A temperature module: 0x2104 defaults to 100 instead of 4000 (§6.9)."""
        return self.ai_kind in ("thermocouple", "pt100", "pt1000")

    @property
    def pot_inputs(self) -> bool:
        """Has potentiometer inputs fed by the module's reference supply (alarm 0x03, §7.6)."""
        return self.ai_kind in ("pot", "configurable")

    @property
    def digital_outputs(self) -> int:
        return self.do + self.dio

    @property
    def digital_inputs(self) -> int:
        return self.di + self.dio


def _t(name: str, description: str, code: int, group: str, **channels: Any) -> ModuleType:
    return ModuleType(name, description, 0x0000FA00 + code, group, **channels)


# §2, in the order the seed prints them (digital column, analog column, encoder modules).
_TYPES = (
    _t("DB16", "16 digital inputs/outputs", 0x01, "digital", dio=16, dio_group_size=4),
    _t("DI16", "16 digital inputs", 0x02, "digital", di=16),
    _t("DO82", "8 digital outputs 2 A", 0x03, "digital", do=8, do_current_a=2.0),
    _t("DO16", "16 digital outputs", 0x04, "digital", do=16),
    _t("AI8D", "8 differential inputs", 0x05, "analog", ai=8, ai_kind="diff_pm10"),
    _t("AI8C", "8 current inputs", 0x06, "analog", ai=8, ai_kind="current"),
    _t("AI8TC", "8 thermocouple inputs", 0x07, "analog", ai=8, ai_kind="thermocouple"),
    _t("AI8PT100", "8 PT100 inputs", 0x08, "analog", ai=8, ai_kind="pt100"),
    _t("AI8PT1000", "8 PT1000 inputs", 0x09, "analog", ai=8, ai_kind="pt1000"),
    _t("AB4P4", "4 potentiometer inputs, 4 analog outputs", 0x0A, "analog",
       ai=4, ai_kind="pot", ao=4, ao_bits=12),
    _t("AB4D4", "4 differential inputs, 4 analog outputs", 0x0B, "analog",
       ai=4, ai_kind="diff_pm10", ao=4, ao_bits=12),
    _t("AB4C4", "4 current inputs, 4 analog outputs", 0x0C, "analog",
       ai=4, ai_kind="current", ao=4, ao_bits=12),
    _t("AI4D", "4 differential inputs", 0x0D, "analog", ai=4, ai_kind="diff_pm10"),
    _t("AI4C", "4 current inputs", 0x0E, "analog", ai=4, ai_kind="current"),
    _t("AO4", "4 analog outputs 12 bit", 0x0F, "analog", ao=4, ao_bits=12),
    _t("AO4H", "4 analog outputs 16 bit", 0x10, "analog", ao=4, ao_bits=16),
    _t("AI4P", "4 potentiometer inputs", 0x11, "analog", ai=4, ai_kind="pot"),
    _t("AI8M", "8 configurable analog inputs", 0x12, "analog", ai=8, ai_kind="configurable"),
    # §2 prints "8 ingressi analog. configurabili + 4 uscite an." and §6.10 gives 0x2106 eight
    # entries for AI8M and AB4M4 alike: 8 inputs, although the name suggests 4 (docs).
    _t("AB4M4", "8 configurable analog inputs + 4 analog outputs", 0x13, "analog",
       ai=8, ai_kind="configurable", ao=4, ao_bits=12),
    _t("AX2", "2 encoder inputs", 0x14, "encoder", encoders=2),
)

CATALOG: dict[str, ModuleType] = {t.name: t for t in _TYPES}
_BY_CODE: dict[int, ModuleType] = {t.product_code: t for t in _TYPES}


def module_type(name: str) -> ModuleType:
    try:
        return CATALOG[name]
    except KeyError:
        raise KeyError(f"unknown FastCAT module type {name!r} (valid: "
                       f"{', '.join(CATALOG)})") from None


def module_type_by_code(code: int) -> ModuleType | None:
    return _BY_CODE.get(code)


def a_module(name: str) -> str:
    """``a DB16``, ``an AI8D``: the article as the name is read out (A-I-8-D)."""
    return f"{'an' if name[:1] in 'AEIOU' else 'a'} {name}"
