"""The drive's 16-bit parameters as data (seed 004 ch. 1 "Quick reference ... Parametri").

Each parameter has the Modbus address of the quick reference (decimal, hex in brackets). The
``% 1-99`` ones have that range; the range of a "Numero" parameter is not printed and is chosen
in docs/servo-drive.md §Parameters. Defaults of d1..d3 are the values of the seed's FC 03
example (ch. 2: d1 = 0x0014, d2 = 0x0032, d3 = 0x0032), the others are chosen there too.

c7 (node), c9 (fieldbus), n1 (CAN bit rate) are read at power-up only (ch. 2 "Configurazione
della rete", ch. 4), d8 (motor) needs a flash save and a restart (ch. 5, note on d8).
0x3802 is not a parameter but the flash-save command address of ch. 2 "Salvataggio su flash".
"""

from __future__ import annotations

from dataclasses import dataclass

from devices.servo.errors import AccessError

SAVE_COMMAND_ADDRESS = 0x3802  # write 0x0011 here (FC 06, or FC 16 as 32 bits) to save
SAVE_COMMAND_VALUE = 0x0011

# c9 values that select a fieldbus (ch. 2, 4, 5, 6).
FIELDBUS_BY_C9: dict[int, str] = {3: "modbus", 5: "canopen", 11: "ethercat", 13: "profinet"}
C9_BY_FIELDBUS: dict[str, int] = {name: code for code, name in FIELDBUS_BY_C9.items()}
# How the dashboard names each fieldbus (the Drive tab's title, the c9 choices).
FIELDBUS_NAMES: dict[str, str] = {"modbus": "Modbus RTU", "canopen": "CANopen",
                                  "ethercat": "EtherCAT", "profinet": "Profinet"}

# The highest node number c7 may take, by c9: a Modbus line assigns 1..90 to the slaves and
# reserves 91..255 (ch. 2 "Configurazione della rete", "Composizione del frame"); any other
# fieldbus takes the whole 1..99 of c7 (ch. 4 CANopen; EtherCAT ignores c7, ch. 5).
MODBUS_NODE_HIGH = 90
NODE_HIGH_BY_C9: dict[int, int] = {3: MODBUS_NODE_HIGH}

# n1 -> CAN bit rate in kBaud (ch. 4 "Configurazione della rete").
CAN_KBAUD_BY_N1: dict[int, int] = {1: 10, 2: 20, 3: 50, 4: 125, 5: 250, 6: 500, 7: 800, 8: 1000}


@dataclass(frozen=True)
class ParameterSpec:
    name: str  # lower case; the seed prints d1, E1, F1, c1, I1, P1, A1, H1, n1, o1
    address: int
    meaning: str
    low: int
    high: int
    default: int
    unit: str = "number"  # "%" for the "% 1-99" ones
    writable: bool = True
    power_up: bool = False  # takes effect at the next power-up only

    @property
    def saveable(self) -> bool:
        # "tutti i parametri del drive che si possono settare anche attraverso il tastierino"
        return self.writable

    def check(self, value: int) -> int:
        if isinstance(value, bool) or not isinstance(value, int):
            raise AccessError("value", f"parameter {self.name}: {value!r} is not an integer")
        if not self.low <= value <= self.high:
            raise AccessError("value", f"parameter {self.name} = {value} is outside "
                                       f"{self.low}..{self.high}")
        return value


def _pct(name: str, address: int, meaning: str, default: int) -> ParameterSpec:
    return ParameterSpec(name, address, meaning, 1, 99, default, unit="%")


def _num(name: str, address: int, meaning: str, low: int = 0, high: int = 99,
         default: int = 0, **kw: bool) -> ParameterSpec:
    return ParameterSpec(name, address, meaning, low, high, default, **kw)


_TABLE: tuple[ParameterSpec, ...] = (
    _pct("d1", 1, "speed loop proportional gain KP", 20),
    _pct("d2", 2, "speed loop integral gain KI", 50),
    _pct("d3", 3, "maximum motor speed Vmax", 50),
    _pct("d4", 4, "speed offset adjustment", 50),
    _pct("d5", 5, "maximum motor current", 99),
    _pct("d6", 6, "peak / nominal current ratio", 50),
    _pct("d7", 7, "I2T function", 50),
    _num("d8", 8, "motor selection", default=1, power_up=True),
    _pct("e1", 9, "maximum nominal speed", 99),
    _pct("e2", 10, "input reference filter", 1),
    _num("e3", 58, "exceptions parameter (6: no parity, 9: Siemens address map)"),
    _num("e4", 55, "reserved"),
    _pct("f1", 11, "maximum acceleration ramp", 50),
    _pct("f2", 12, "maximum deceleration ramp", 50),
    _pct("f3", 13, "emergency ramp", 50),
    _num("c1", 14, "RTE output pulses selection"),
    _num("c2", 15, "motor rotation direction", high=1),
    _num("c3", 16, "control type (0 speed, 1 torque)", high=1),
    _num("c4", 17, "resolver pole pairs", low=1, default=1),
    _num("c5", 18, "encoder pulses per revolution selection"),
    _num("c6", 19, "transducer type"),
    _num("c7", 20, "network node number", low=1, default=1, power_up=True),
    _num("c8", 21, "not used (miniECO: CN1 input assignment)", high=6, default=6),
    _num("c9", 22, "operating mode / fieldbus (3 Modbus, 5 CANopen, 11 EtherCAT, 13 Profinet)",
         default=3, power_up=True),
    _pct("i1", 35, "position loop proportional gain", 50),
    _pct("i2", 36, "position loop integral gain", 10),
    _pct("i3", 37, "position loop derivative gain", 10),
    _pct("i4", 38, "inertia compensation", 10),
    _num("i5", 39, "position error timeout (1/100 s)", default=10),
    _num("i6", 90, "external encoder mode"),
    _num("i7", 99, "reserved"),
    _num("o1", 81, "instantaneous current (%)", high=0xFFFF, writable=False),
    _num("o2", 82, "RMS current (%)", high=0xFFFF, writable=False),
    _num("o3", 83, "overload (% of I2T)", high=0xFFFF, writable=False),
    _num("p1", 41, "pulses per motor revolution, high part"),
    _num("p2", 42, "pulses per motor revolution, low part"),
    _num("p3", 43, "maximum following error (degrees), high part"),
    _num("p4", 44, "maximum following error (degrees), low part"),
    _num("p5", 45, "acceleration ramp (ms / 100 rpm)", default=10),
    _num("p6", 46, "deceleration ramp (ms / 100 rpm)", default=10),
    _num("p7", 47, "maximum speed (rpm / 100)", low=1, default=30),
    _num("a1", 48, "master encoder marks, high part"),
    _num("a2", 49, "master encoder marks, low part"),
    _num("a3", 50, "ratio numerator", low=1, default=1),
    _num("a4", 51, "ratio denominator", low=1, default=1),
    _num("a5", 52, "maximum following error (degrees), high part"),
    _num("a6", 53, "maximum following error (degrees), low part"),
    _num("h1", 59, "homing method"),
    _pct("h2", 60, "switch search speed (% of nominal)", 10),  # printed (0x0030); 60 = 0x003C
    _pct("h3", 61, "marker search speed (per mille of nominal)", 10),
    _num("h4", 62, "acceleration / deceleration ramp time (ms / 100 rpm)", default=10),
    _num("h5", 63, "position offset sign", high=1),
    _num("h6", 64, "position offset in master encoder pulses, ten-thousands"),
    _num("h7", 65, "position offset in master encoder pulses, hundreds"),
    _num("h8", 66, "position offset in master encoder pulses, units"),
    _num("h9", 67, "manual position offset calibration utility"),
    _num("n1", 40, "CAN bit rate (1..8: 10, 20, 50, 125, 250, 500, 800, 1000 kBaud)", low=1,
         high=8, default=6, power_up=True),
)

PARAMETERS: dict[int, ParameterSpec] = {spec.address: spec for spec in _TABLE}
PARAMETER_BY_NAME: dict[str, ParameterSpec] = {spec.name: spec for spec in _TABLE}
assert len(PARAMETERS) == len(_TABLE), "two parameters share an address"


def parameter_spec(address: int) -> ParameterSpec:
    spec = PARAMETERS.get(address) if isinstance(address, int) else None
    if spec is None:
        raise AccessError("address", f"there is no parameter at address {address!r}")
    return spec


def parameter_by_name_or_address(key: str | int) -> ParameterSpec:
    """``"d3"``, ``"D3"``, ``3``, ``"3"`` or ``"0x0003"`` -> the spec of d3."""
    if isinstance(key, str):
        text = key.strip().lower()
        if text in PARAMETER_BY_NAME:
            return PARAMETER_BY_NAME[text]
        try:
            key = int(text, 0)
        except ValueError:
            raise AccessError("address", f"there is no parameter {key!r} (names: "
                                         f"{', '.join(sorted(PARAMETER_BY_NAME))})") from None
    return parameter_spec(key)


def node_range(c9: int) -> tuple[int, int]:
    """The node numbers c7 may take on the fieldbus c9 selects: 1..90 on Modbus, else c7's own
    1..99."""
    spec = PARAMETER_BY_NAME["c7"]
    return spec.low, NODE_HIGH_BY_C9.get(c9, spec.high)


def check_node_number(c7: int, c9: int) -> None:
    """c7 against the fieldbus c9 selects (the per-parameter range is the widest, 1..99)."""
    high = NODE_HIGH_BY_C9.get(c9)
    if high is not None and c7 > high:
        raise AccessError("value", f"parameter c7 = {c7} is outside 1..{high} with c9 = {c9} "
                                   f"({FIELDBUS_BY_C9[c9]})")


def default_parameters(overrides: dict[str, int] | None = None) -> dict[int, int]:
    values = {spec.address: spec.default for spec in _TABLE}
    for name, value in (overrides or {}).items():
        spec = PARAMETER_BY_NAME[name]
        values[spec.address] = spec.check(value)
    return values
