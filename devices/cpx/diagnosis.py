"""What the CPX-E-EC reports about the faults its modules see: 0x1001 / 0x1002, the status bits,
the diagnosis history 0x10F3, emergencies and the I/O diagnostic interface.

Seed 002 §2.4.2 (status bits), §2.4.3 (I/O diagnostic interface), §2.5.2 (history), §2.5.3
(emergency). A fault appearing is an error message (Text-ID 0x3700 + CPX error number) and,
when 0x10F3:5 bit 0 is set, an emergency; a fault going is an information message with CPX
error 0 (unless 0x2401 "Filter No Error" is set) and, once no fault is left, the "no error"
emergency 0x0000 of Tab. 21. Within the reported errors the most severe class comes first,
then the lowest module number (CPX-E system description; it drives SF and the interface).
The messages and emergencies of CPX errors are the CPX-E system's error messages, which reach
the PLC only with the I/O diagnostic interface active (§2.5, the note before §2.5.1): the
``reports`` predicate says so; the registers, the status bits and the alarm events do not
depend on it (docs/cpx-e-ec.md choice 33).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass

from devices.cpx.catalog import ModuleKind, ModuleType
from devices.cpx.codes import (
    CAUSES,
    CPX_TEXT_ID_BASE,
    DIAG_CODE_CPX,
    DIAG_CODE_DS401,
    EMCY_GENERAL,
    EMCY_NO_ERROR,
    REG_GENERIC,
    ST_ANALOG,
    ST_INPUT,
    ST_OUTPUT,
    Cause,
    DiagType,
    diag_code,
    emcy_code_for,
)
from devices.cpx.history import DiagHistory
from devices.cpx.leds import module_error_led
from devices.cpx.messages import DiagMessage, channel_param, emergency_frame
from devices.cpx.modules import ModuleFault
from devices.events import AlarmChanged, EmergencySent, Event, LogLine, fmt_hex
from devices.od import DataType

MAILBOX_DEPTH = 16  # emergencies kept for the master while its mailbox does not run
# I/O diagnostic interface function numbers (CPX-E system description; FieldRig subset).
FN_FIRST_MODULE = 1936  # module number of the first faulty module
FN_STATUS_BITS = 1937  # the 8 status bits
FN_ERROR_NUMBER = 1938  # error number of the first faulty module
FN_MODULE_BASE = 2008  # 2008 + 4m + 0 status bits, + 1 error number, + 2 first channel
STI_READ_REQUEST = 0x8000  # output word bit 15; bits 0-12 the function number
STI_FUNCTION_MASK = 0x1FFF


def module_bit(mtype: ModuleType, cause: Cause) -> int:
    """Tab. 23 bits 0-3: the kind of module the error is on."""
    if cause.module_bit is not None:
        return cause.module_bit
    if mtype.kind is ModuleKind.ANALOG:
        return ST_ANALOG
    return ST_OUTPUT if mtype.has_outputs else ST_INPUT


@dataclass(frozen=True)
class ActiveError:
    fault: ModuleFault
    mtype: ModuleType

    @property
    def cause(self) -> Cause:
        return CAUSES[self.fault.cause]

    @property
    def status_bits(self) -> int:
        return module_bit(self.mtype, self.cause) | self.cause.error.error_bit

    @property
    def register(self) -> int:
        return REG_GENERIC | self.cause.register_bit

    @property
    def params(self) -> tuple[tuple[DataType, int], ...]:
        """Tab. 16: parameter 1 the CPX module number, parameter 2 the channel."""
        out = [(DataType.UNSIGNED8, self.fault.module)]
        if self.fault.channel is not None:
            out.append((DataType.UNSIGNED8,
                        channel_param(self.fault.channel, self.fault.output)))
        return tuple(out)

    @property
    def priority(self) -> tuple[int, int]:
        return (-self.cause.error.error_class, self.fault.module)


class Diagnosis:
    def __init__(self, device: str, emit: Callable[[Event], None], history: DiagHistory,
                 filter_no_error: Callable[[], bool], reports: Callable[[], bool]) -> None:
        self.device = device
        self.emit = emit
        self.history = history
        self.filter_no_error = filter_no_error
        self.reports = reports
        self.active: list[ActiveError] = []
        self.mailbox: list[bytes] = []

    # ---- aggregates -------------------------------------------------------------------------
    @property
    def error_register(self) -> int:
        """0x1001 (Tab. 22)."""
        out = 0
        for error in self.active:
            out |= error.register
        return out

    @property
    def status_bits(self) -> int:
        """0x1002 and the status-bit inputs (Tab. 23, §2.4.2)."""
        out = 0
        for error in self.active:
            out |= error.status_bits
        return out

    def ranked(self) -> list[ActiveError]:
        return sorted(self.active, key=lambda e: e.priority)

    @property
    def error_class(self) -> int:
        return max((e.cause.error.error_class for e in self.active), default=0)

    # ---- changes ----------------------------------------------------------------------------
    def update(self, faults: Sequence[tuple[ModuleFault, ModuleType]], t_us: int,
               t_ns: int) -> None:
        now = [ActiveError(f, m) for f, m in faults]
        gone = [e for e in self.active if e not in now]
        new = [e for e in now if e not in self.active]
        self.active = now
        for error in gone:
            self._gone(error, t_us, t_ns)
        for error in new:
            self._raised(error, t_us, t_ns)
        if gone and not self.active and self.reports():
            self._emergency(emergency_frame(EMCY_NO_ERROR, 0, 0, 0, 0, 0), t_us)

    def clear(self) -> None:
        """Power lost: the RAM state goes (the history object is rebuilt by the caller)."""
        self.active = []
        self.mailbox = []

    def halt(self, t_us: int) -> None:
        """The application controller stops (power lost, AC failure): it diagnoses nothing
        from now on, so what it diagnosed is no longer shown; the alarms clear. Nothing goes
        into 0x10F3 or the mailbox: the controller that would write them does not run, and
        the start that ends the stop empties them (docs/cpx-e-ec.md choice 39)."""
        for error in self.active:
            self._alarm(error, False, t_us)
        self.active = []

    def _alarm(self, error: ActiveError, active: bool, t_us: int) -> None:
        cpx = error.cause.error
        self.emit(AlarmChanged(t_us, self.device, code=fmt_hex(cpx.text_id, 4),
                               name=cpx.symbol, active=active, module=error.fault.module))

    def _raised(self, error: ActiveError, t_us: int, t_ns: int) -> None:
        cpx = error.cause.error
        self._alarm(error, True, t_us)
        if not self.reports():
            return
        self.store(DiagMessage(diag_code(DIAG_CODE_CPX, cpx.number), DiagType.ERROR,
                               cpx.text_id, t_ns, error.params), t_us)
        self._emergency(emergency_frame(emcy_code_for(error.cause), self.error_register,
                                        self.status_bits, error.fault.module, cpx.number,
                                        error.fault.channel or 0), t_us)

    def _gone(self, error: ActiveError, t_us: int, t_ns: int) -> None:
        self._alarm(error, False, t_us)
        if self.reports() and not self.filter_no_error():
            self.store(DiagMessage(diag_code(DIAG_CODE_CPX, 0), DiagType.INFO,
                                   CPX_TEXT_ID_BASE, t_ns, error.params), t_us)

    def report(self, text_id: int, dtype: DiagType, t_us: int, t_ns: int,
               params: tuple[tuple[DataType, int], ...] = ()) -> None:
        """An EtherCAT-side message of Tab. 17 (ident check, sync managers, bus cycle)."""
        self.store(DiagMessage(diag_code(DIAG_CODE_DS401, EMCY_GENERAL), dtype, text_id,
                               t_ns, params), t_us)

    def store(self, message: DiagMessage, t_us: int) -> None:
        if self.history.add(message):
            self.emit(LogLine(t_us, self.device, text=f"0x10F3: {message.text()}"))

    def _emergency(self, frame: bytes, t_us: int) -> None:
        if not self.history.emergency_enabled:  # Tab. 19: bit 0 = 0, no emergency
            return
        code = int.from_bytes(frame[:2], "little")
        self.emit(EmergencySent(t_us, self.device, code=code, register=frame[2],
                                data=frame[3:]))
        self.mailbox = [*self.mailbox, frame][-MAILBOX_DEPTH:]

    # ---- I/O diagnostic interface -----------------------------------------------------------
    def interface_word(self, request: int) -> int:
        """§2.4.3 input word for the output word ``request`` (docs/cpx-e-ec.md)."""
        if not request & STI_READ_REQUEST:
            return 0
        return STI_READ_REQUEST | self.function_value(request & STI_FUNCTION_MASK)

    def function_value(self, number: int) -> int:
        ranked = self.ranked()
        first = ranked[0] if ranked else None
        if number == FN_FIRST_MODULE:
            return first.fault.module if first else 0
        if number == FN_STATUS_BITS:
            return self.status_bits
        if number == FN_ERROR_NUMBER:
            return first.cause.error.number if first else 0
        if number >= FN_MODULE_BASE:
            module, item = divmod(number - FN_MODULE_BASE, 4)
            mine = [e for e in ranked if e.fault.module == module]
            if not mine:
                return 0
            if item == 0:
                bits = 0
                for e in mine:
                    bits |= e.status_bits
                return bits
            if item == 1:
                return mine[0].cause.error.number
            if item == 2:
                channels = [e.fault.channel for e in mine if e.fault.channel is not None]
                return min(channels) if channels else 0
        return 0

    def of_module(self, module: int) -> list[dict[str, object]]:
        """What is diagnosed on module ``module`` now: the causes behind its error LED."""
        return [{"cause": e.fault.cause, "channel": e.fault.channel}
                for e in self.ranked() if e.fault.module == module]

    def error_led(self, module: int) -> dict[str, object]:
        """Module ``module``'s red LED: the worst cause diagnosed on it (leds.py)."""
        return module_error_led([(e.fault.cause, e.fault.channel) for e in self.active
                                 if e.fault.module == module])

    def snapshot(self) -> dict[str, object]:
        return {"error_register": self.error_register, "status_bits": self.status_bits,
                "error_class": self.error_class,
                "errors": [{"module": e.fault.module, "cause": e.fault.cause,
                            "channel": e.fault.channel, "output": e.fault.output,
                            "cpx_error": e.cause.error.number, "name": e.cause.error.symbol,
                            "text": e.cause.error.text,
                            "emcy_code": fmt_hex(emcy_code_for(e.cause), 4)}
                           for e in self.ranked()],
                "mailbox": len(self.mailbox)}
