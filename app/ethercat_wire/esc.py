"""Emulated EtherCAT slave controllers: one `Esc` per slave, a `Line` that runs frames past them.

An ESC here holds no device logic: it is 64 KiB of memory with the side effects a real ESC has
on reads and writes (ethercat-wire-notes.md). What the device must decide goes to process A as
a message in `Line.outbox` (AL control, mailbox requests, changed outputs, DC settings); what A
decides comes back through `Esc.set_al_status`, `queue_mailbox`, `set_inputs`.

Working counters (ETG.1000.4 §5.4, notes "Frames and datagrams"): read +1, write +1,
read-write +3 per addressed slave; LRW +1 if a read FMMU overlapped and +2 if a write FMMU did.
"""

from __future__ import annotations

import logging
import struct
from collections import deque

from app.ethercat_wire import dc, messages
from app.ethercat_wire import registers as R
from app.ethercat_wire import sii as sii_image
from app.ethercat_wire.damage import Damage, WireCounters
from app.ethercat_wire.datagrams import Cmd, Datagram, get_wkc, parse, set_adp, set_wkc
from app.ethercat_wire.description import SlaveDescription
from devices.master.esc_errors import CLEARED_TOGETHER

logger = logging.getLogger(__name__)

_U16 = struct.Struct("<H")
_U64 = struct.Struct("<Q")
MAILBOX_HEADER = 6
_RO = R.READ_ONLY
_RO_MASK = bytes(1 if any(a <= i < b for a, b in _RO) else 0 for i in range(R.PROCESS_RAM))
_SYNC_REGS = (R.DC_ACTIVATION, R.DC_CYCLE0 + 4)


class Esc:
    """One slave's ESC: register/process memory plus read and write side effects."""

    def __init__(self, position: int, desc: SlaveDescription, sii: bytes,
                 clock: dc.DcClock, outbox: list[tuple]) -> None:
        self.position = position
        self.desc = desc
        self.sii = bytearray(sii)
        self.clock = clock
        self.outbox = outbox
        self.mem = R.power_on(desc, _U16.unpack_from(self.sii, sii_image.ALIAS_BYTE)[0])
        self.station = 0
        self.index = position  # index among the slaves visible on the wire
        self.downstream = 0  # visible slaves after this one
        self.sms = R.SmRoles()
        self._sm_registers: tuple[tuple[int, int, int, bool], ...] = ()
        self.fmmus: tuple[R.FmmuMap, ...] = ()
        self._plan: list[tuple[int, int, int, bool, bool, bool]] = []
        self._bit_fmmus: tuple[R.FmmuMap, ...] = ()
        self.exchanges = 0  # process-data datagrams that hit this slave's FMMUs
        self._mbx_queue: deque[bytes] = deque()
        self._mbx_full: bytes | None = None  # the message now in SM1
        self._mbx_last: bytes | None = None  # for a repeat request
        self._rx_counter = 0  # last mailbox counter taken from SM0 (1..7; 0 = none yet)
        self._outputs = b""
        self._inputs = b""
        self.master_time: tuple[int, int] | None = None  # (time written to 0x0910, local ns)
        self.counters = WireCounters()  # 0x0300-0x0313: the model's and the wire's counts
        self._mailbox_sms = tuple(n for n, sm in enumerate(desc.sync_managers)
                                  if sii_image.sm_type(sm) in (sii_image.SM_TYPE_MBX_OUT,
                                                               sii_image.SM_TYPE_MBX_IN))
        self._deactivate_mailbox(True)  # powered up in INIT

    # ---- what process A tells the ESC ----
    def set_al_status(self, status: int, code: int) -> None:
        was = _U16.unpack_from(self.mem, R.AL_STATUS)[0] & R.AL_STATE_MASK
        _U16.pack_into(self.mem, R.AL_STATUS, status & 0xFFFF)
        _U16.pack_into(self.mem, R.AL_STATUS_CODE, code & 0xFFFF)
        init = status & R.AL_STATE_MASK == R.AL_STATE_INIT
        if init and was != R.AL_STATE_INIT:
            # the slave stack stopped its mailbox (SSC MBX_StopMailboxHandler: SM1 disabled,
            # send queue freed): what the master has not read is lost, as in the model
            self._mbx_queue.clear()
            self._mbx_full = self._mbx_last = None
            self._set_mbx_status(self.sms.mbx_in, False)
        self._deactivate_mailbox(init)

    def _mailbox_stopped(self) -> bool:
        """INIT runs no mailbox (ETG.1000.6): the stack starts it at INIT -> PREOP."""
        return _U16.unpack_from(self.mem, R.AL_STATUS)[0] & R.AL_STATE_MASK == R.AL_STATE_INIT

    def _deactivate_mailbox(self, off: bool) -> None:
        """SM PDI control (offset 7) bit 0 of the mailbox SMs: set while the slave stack keeps
        them deactivated from its side (INIT; SSC DisableSyncManChannel), so a master's write
        to SM0 then is plain memory, no mailbox event, and nothing reaches the model."""
        for n in self._mailbox_sms:
            pdi = R.SM0 + R.SM_SIZE * n + 7
            self.mem[pdi] = self.mem[pdi] | 0x01 if off else self.mem[pdi] & ~0x01 & 0xFF

    def set_alias(self, alias: int | None) -> None:
        """The slave restarted (an ESC power-up): with a configured station alias of its own,
        SII word 4 (and the CRC of the ESC configuration area) rewritten; None: the stored
        word 4 stays (the CPX-E-EC at switch 0). 0x0012 is loaded from word 4 either way."""
        if alias is not None:
            sii_image.set_alias(self.sii, alias)
        stored = _U16.unpack_from(self.sii, sii_image.ALIAS_BYTE)[0]
        _U16.pack_into(self.mem, R.STATION_ALIAS, stored)

    def queue_mailbox(self, data: bytes) -> None:
        if self._mailbox_stopped():
            return  # a reply or emergency overtaken by the return to INIT: the stack drops it
        self._mbx_queue.append(bytes(data))
        self._load_mailbox()

    def set_inputs(self, data: bytes) -> None:
        self._inputs = bytes(data)
        self._place_inputs()

    def set_error_counters(self, data: bytes, seq: int) -> None:
        """0x0300-0x0313 as the model counts them (a damaged cable, lost links), the wire's
        count batches up to ``seq`` included (damage.py)."""
        self.counters.from_model(data, seq)
        self.show_error_counters()

    def show_error_counters(self) -> None:
        self.mem[R.ERROR_COUNTERS:R.ERROR_COUNTERS_END] = self.counters.registers()

    def set_last(self, last: bool) -> None:
        _U16.pack_into(self.mem, R.DL_STATUS, R.dl_status(last))

    # ---- what the master does ----
    def read(self, ado: int, length: int) -> bytes:
        end = ado + length
        if ado < R.DC_SPEED_COUNTER and end > R.DC_SYSTEM_TIME:
            self._dc_read(ado, end)
        data = bytes(self.mem[ado:end])
        if end > R.MEMORY_SIZE:  # past the 64 KiB: nothing there, the datagram keeps its size
            data = data.ljust(length, b"\0")
        mbx = self.sms.mbx_in
        if mbx is not None and self._mbx_full is not None and ado <= mbx.last < end:
            self._mailbox_read()
        return data

    def write(self, ado: int, data: bytes) -> None:
        end = ado + len(data)
        if end > R.MEMORY_SIZE:
            data, end = data[:R.MEMORY_SIZE - ado], R.MEMORY_SIZE
        if ado >= R.PROCESS_RAM:
            self.mem[ado:end] = data
            self._after_ram_write(ado, end)
            return
        if _RO_MASK.find(1, ado, end) >= 0:
            saved = [(a, b, self.mem[a:b]) for a, b in _RO if a < end and b > ado]
            self.mem[ado:end] = data
            for a, b, old in saved:
                self.mem[a:b] = old
        else:
            self.mem[ado:end] = data
        self._after_register_write(ado, end, data)
        if end > R.PROCESS_RAM:
            self._after_ram_write(R.PROCESS_RAM, end)

    def _after_register_write(self, ado: int, end: int, data: bytes) -> None:
        if ado < R.STATION_ADDRESS + 2 and end > R.STATION_ADDRESS:
            station = _U16.unpack_from(self.mem, R.STATION_ADDRESS)[0]
            if station != self.station:  # the address the master gives the slave: A's too
                self.station = station
                self.outbox.append((messages.STATION, self.position, station))
        if ado < R.ERROR_COUNTERS_END and end > R.ERROR_COUNTERS:
            self._error_counters_written(ado, end)
        if ado < R.AL_CONTROL + 2 and end > R.AL_CONTROL:
            value = _U16.unpack_from(self.mem, R.AL_CONTROL)[0]
            self.outbox.append((messages.AL_CONTROL, self.position, value))
        if ado <= R.EEPROM_CONTROL + 1 and end > R.EEPROM_CONTROL:
            self._eeprom_command()
        if ado < R.FMMU0 + R.FMMU_SIZE * R.FMMU_MAX and end > R.FMMU0:
            self.fmmus = R.decode_fmmus(self.mem, self.desc.fmmu_count)
            self._replan()
        if ado < R.SM0 + R.SM_SIZE * R.SM_MAX and end > R.SM0:
            self._sm_config_written(ado, end)
        if ado >= R.DC_RECEIVE_TIME_PORT0 and end <= R.DC_CYCLE0 + 8:
            self._dc_write(ado, end, data)

    def _error_counters_written(self, ado: int, end: int) -> None:
        """The ESC's rule: a write clears each block it touches, whatever the value (here at
        once, for the master's next read); the model clears the same."""
        for first, last in CLEARED_TOGETHER:
            if ado < last and end > first:
                self.mem[first:last] = bytes(last - first)
        seq = self.counters.write(ado, end - ado)
        self.outbox.append((messages.ESC_ERRORS_WRITE, self.position, ado, end - ado, seq))

    def _dc_read(self, ado: int, end: int) -> None:
        if ado < R.DC_RECEIVE_TIME_PU and end > R.DC_SYSTEM_TIME:
            dc.refresh_system_time(self.mem, self.clock.local_ns())
        if end > R.DC_SYSTEM_DIFF and self.master_time is not None:
            dc.take_master_time(self.mem, *self.master_time)
            self.master_time = None

    def _dc_write(self, ado: int, end: int, data: bytes) -> None:
        if not self.desc.dc_supported:
            return
        if ado == R.DC_RECEIVE_TIME_PORT0:
            dc.latch(self.mem, self.clock.local_ns(), self.index, self.downstream)
        if ado <= R.DC_SYSTEM_TIME and end >= R.DC_SYSTEM_TIME + 4:
            raw = bytes(data[R.DC_SYSTEM_TIME - ado:R.DC_SYSTEM_TIME - ado + 8]).ljust(8, b"\0")
            self.master_time = None
            dc.take_master_time(self.mem, _U64.unpack(raw)[0], self.clock.local_ns())
        if dc.touches_sync(ado, end):
            self.outbox.append((messages.DC, self.position, dc.sync_settings(self.mem)))

    def _after_ram_write(self, ado: int, end: int) -> None:
        sms = self.sms
        mbx = sms.mbx_out
        if mbx is not None and ado <= mbx.last < end and not self._mailbox_stopped():
            self._mailbox_written(mbx)
        out = sms.outputs
        if out is not None and ado < out.end and end > out.start:
            image = bytes(self.mem[out.start:out.end])
            if image != self._outputs:
                self._outputs = image
                self.outbox.append((messages.OUTPUTS, self.position, image))

    # ---- SII EEPROM interface (0x0500-0x050F) ----
    def _eeprom_command(self) -> None:
        control = _U16.unpack_from(self.mem, R.EEPROM_CONTROL)[0]
        command = control & R.EEPROM_CMD_MASK
        word = _U16.unpack_from(self.mem, R.EEPROM_ADDRESS)[0]
        if command == R.EEPROM_CMD_READ:
            chunk = bytes(self.sii[word * 2:word * 2 + 8]).ljust(8, b"\xff")
            self.mem[R.EEPROM_DATA:R.EEPROM_DATA + 8] = chunk
        elif command == R.EEPROM_CMD_WRITE and control & R.EEPROM_WRITE_ENABLE:
            if word * 2 + 2 > len(self.sii):
                self.sii.extend(b"\xff" * (word * 2 + 2 - len(self.sii)))
            self.sii[word * 2:word * 2 + 2] = self.mem[R.EEPROM_DATA:R.EEPROM_DATA + 2]
        # every command completes at once: not busy, no error, 8-byte reads
        _U16.pack_into(self.mem, R.EEPROM_CONTROL, R.EEPROM_READ_8_BYTES)

    # ---- sync managers and the mailbox transport ----
    def _sm_config_written(self, ado: int, end: int) -> None:
        registers = R.sm_registers(self.mem, max(4, len(self.desc.sync_managers)))
        if registers != self._sm_registers:  # the slave checks them at its transitions
            self._sm_registers = registers
            self.outbox.append((messages.SM, self.position, registers))
        before = self.sms
        self.sms = R.decode_sms(self.mem, max(4, len(self.desc.sync_managers)))
        self._replan()
        if before.mbx_in != self.sms.mbx_in:
            # a disabled or moved SM1 loses what it held (a new master starts clean)
            self._mbx_full = None
            self._set_mbx_status(before.mbx_in, False)
            if self.sms.mbx_in is None:
                self._mbx_queue.clear()
            self._load_mailbox()
        if before.mbx_out != self.sms.mbx_out:
            self._rx_counter = 0
        if before.inputs != self.sms.inputs:
            self._place_inputs()
        mbx = self.sms.mbx_in
        if mbx is not None:
            act = R.SM0 + R.SM_SIZE * mbx.index + 6
            if ado <= act < end:
                self._repeat_request(act)

    def _repeat_request(self, act: int) -> None:
        """SOEM toggles activate bit 1 when a mailbox read got lost: put the last message back
        and acknowledge by mirroring the bit in the PDI control byte (act + 1)."""
        want = self.mem[act] & R.SM_REPEAT_REQUEST
        if (self.mem[act + 1] & R.SM_REPEAT_REQUEST) == want:
            return
        if self._mbx_last is not None and self._mbx_full is None:
            self._put_mailbox(self._mbx_last)
        self.mem[act + 1] = (self.mem[act + 1] & ~R.SM_REPEAT_REQUEST) | want

    def _mailbox_written(self, sm: R.SmConfig) -> None:
        buf = self.mem[sm.start:sm.end]
        length = _U16.unpack_from(buf, 0)[0]
        counter = (buf[5] >> 4) & 0x07
        if counter and counter == self._rx_counter:
            return  # SOEM resent a datagram whose answer it missed: handled already
        self._rx_counter = counter
        size = min(MAILBOX_HEADER + length, sm.length)
        self.outbox.append((messages.MAILBOX, self.position, bytes(buf[:size])))

    def _mailbox_read(self) -> None:
        self._mbx_full = None
        self._set_mbx_status(self.sms.mbx_in, False)
        self._load_mailbox()

    def _load_mailbox(self) -> None:
        if self._mbx_full is None and self._mbx_queue and self.sms.mbx_in is not None:
            self._put_mailbox(self._mbx_queue.popleft())

    def _put_mailbox(self, data: bytes) -> None:
        sm = self.sms.mbx_in
        if sm is None:
            return
        if len(data) > sm.length:
            logger.warning("slave %d: %d-byte mailbox reply cut to SM1's %d bytes",
                           self.position, len(data), sm.length)
        self.mem[sm.start:sm.end] = data[:sm.length].ljust(sm.length, b"\0")
        self._mbx_full = self._mbx_last = data
        self._set_mbx_status(sm, True)

    def _set_mbx_status(self, sm: R.SmConfig | None, full: bool) -> None:
        if sm is None:
            return
        status = R.SM0 + R.SM_SIZE * sm.index + 5
        if full:
            self.mem[status] |= R.SM_STATUS_MAILBOX_FULL
        else:
            self.mem[status] &= ~R.SM_STATUS_MAILBOX_FULL & 0xFF

    def _place_inputs(self) -> None:
        sm = self.sms.inputs
        if sm is not None and self._inputs:
            n = min(len(self._inputs), sm.length)
            self.mem[sm.start:sm.start + n] = self._inputs[:n]

    # ---- logical addressing through the FMMUs ----
    def _replan(self) -> None:
        """Byte-wise FMMUs as plain tuples for the cyclic path: (log start, log end, phys
        start, readable, writable, plain). `plain` False: the physical range holds a mailbox
        end or the outputs SM, so the access goes through the side effects."""
        watched = [sm for sm in (self.sms.mbx_in, self.sms.mbx_out, self.sms.outputs)
                   if sm is not None]
        plan = []
        for fm in self.fmmus:
            if fm.bits is not None:
                continue
            p_end = fm.phys_start + fm.log_end - fm.log_start
            if p_end > R.MEMORY_SIZE:
                continue  # a map past the 64 KiB does not exist on a real ESC either
            plain = not any(sm.start < p_end and sm.end > fm.phys_start for sm in watched)
            plan.append((fm.log_start, fm.log_end, fm.phys_start,
                         bool(fm.kind & R.FMMU_READ), bool(fm.kind & R.FMMU_WRITE), plain))
        self._plan = plan
        self._bit_fmmus = tuple(fm for fm in self.fmmus if fm.bits is not None)

    def logical(self, cmd: int, address: int, frame: bytearray, offset: int, length: int) -> int:
        """Apply LRD/LWR/LRW [address, address+length) to this slave; the WKC increment."""
        read = wrote = False
        end = address + length
        mem = self.mem
        can_write = cmd != Cmd.LRD
        can_read = cmd != Cmd.LWR
        for log_start, log_end, phys, readable, writable, plain in self._plan:
            lo = address if address > log_start else log_start
            hi = end if end < log_end else log_end
            if lo >= hi:
                continue
            f0 = offset + lo - address
            p0 = phys + lo - log_start
            n = hi - lo
            if writable and can_write:
                mem[p0:p0 + n] = frame[f0:f0 + n]
                if not plain:
                    self._after_ram_write(p0, p0 + n)
                wrote = True
            if readable and can_read:
                frame[f0:f0 + n] = mem[p0:p0 + n] if plain else self.read(p0, n)
                read = True
        for fm in self._bit_fmmus:
            if fm.log_start >= end or fm.log_end <= address:
                continue
            lo, hi = max(address, fm.log_start), min(end, fm.log_end)
            r, w = R.copy_bits(mem, fm, cmd != Cmd.LRD, cmd != Cmd.LWR, frame,
                                 offset - address, lo, hi)
            read |= r
            wrote |= w
            if w:
                self._after_ram_write(fm.phys_start, fm.phys_start + fm.log_end - fm.log_start + 1)
        if read or wrote:
            self.exchanges += 1
        if cmd == Cmd.LRW:
            return (1 if read else 0) + (2 if wrote else 0)
        return 1 if (read if cmd == Cmd.LRD else wrote) else 0


class Line:
    """The slaves of one wire in line order; `process(frame)` answers a frame in place.

    `link_ok[pos]` False means the cable into `pos` is pulled or the slave is off: from there
    on the slaves vanish and the frame comes back from the last one on its path (``path``),
    untouched by the rest. With no slave on the path the frame is dropped (the master sees its
    link down). `silent[pos]` True means the slave is powered and on the path but does not
    answer (a drive whose c9 did not select EtherCAT at power-up, seed 004 ch. 2): its ESC
    passes the frame on, whatever its application does, and takes no datagram (no working
    counter, no auto-increment position, no register read or written), as the built-in
    master's line has it (devices/master/line.py ``frame_path``). ``visible``: the slaves on
    the path that answer. A damaged cable spoils frames along the path, silent slaves included.
    The frames that crossed a silent slave go to A with the exchanges (:meth:`take_passed`):
    its L/A LEDs show them (docs/ethercat-coe.md "LEDs of a drive with c9 != 11").
    """

    def __init__(self, escs: list[Esc], outbox: list[tuple]) -> None:
        self.escs = escs
        self.outbox = outbox
        self.link_ok = [True] * len(escs)
        self.silent = [False] * len(escs)
        self.path: list[Esc] = []
        self.visible: list[Esc] = []
        self.frames = 0
        self.pd_frames = 0  # frames carrying LRD/LWR/LRW
        self.wkc_errors = 0  # process-data datagrams short of the WKC of the whole line
        self.damage = Damage()  # the damaged cables, as the model says (damage.py)
        for esc in escs:  # the master's writes numbered with the batches
            esc.counters.numbers = self.damage.numbers
        self.passing: list[int] = []  # the silent slaves on the path
        self._passed: dict[int, int] = {}  # frames that crossed them, not yet taken
        self._passed_at = 0  # ``frames`` when last credited to ``passing``
        self._relink()

    def set_link(self, position: int, up: bool) -> None:
        """Down: the slaves from `position` on vanish. Up: every cut from `position` on heals."""
        if up:
            self.link_ok[position:] = [True] * (len(self.escs) - position)
        else:
            self.link_ok[position] = False
        self._relink()

    def set_silent(self, position: int, silent: bool) -> None:
        """The slave at `position` stops (True) or starts (False) answering; its ESC passes
        frames on either way."""
        self.silent[position] = silent
        self._relink()

    @property
    def spoiled(self) -> int:
        """Frames a damaged cable spoiled (not answered) in this run."""
        return self.damage.spoiled

    def set_damage(self, shares: dict[int, float], seed: int, run: int) -> None:
        """A's damaged cables; a new run (a scenario load) drops what the old one counted and
        A has not taken, and starts the statistics again (A's master is a fresh one)."""
        if self.damage.set(shares, seed, run):
            for esc in self.escs:
                esc.counters.new_run()
                esc.show_error_counters()
            self.frames = self.wkc_errors = self._passed_at = 0
            self._passed.clear()  # the old run's: crossed the slave models of before the load

    def take_esc_counts(self) -> tuple[int, dict[int, bytes]] | None:
        return self.damage.take(self.escs)

    def take_passed(self) -> dict[int, int]:
        """Frames that crossed each silent slave since the last call: every frame answered
        since then, counted from ``frames`` here rather than per frame (process() pays
        nothing for it). A spoiled frame is not answered and does not count (the built-in
        master's lost frame passes no silent slave either)."""
        self._credit_passed()
        passed, self._passed = self._passed, {}
        return passed

    def _credit_passed(self) -> None:
        n = self.frames - self._passed_at
        self._passed_at = self.frames
        if n > 0:
            for position in self.passing:
                self._passed[position] = self._passed.get(position, 0) + n

    def _relink(self) -> None:
        self._credit_passed()  # the frames so far crossed the silent slaves of the old path
        n = next((i for i, ok in enumerate(self.link_ok) if not ok), len(self.escs))
        self.path = self.escs[:n]
        self.visible = [esc for esc in self.path if not self.silent[esc.position]]
        self.passing = [esc.position for esc in self.path if self.silent[esc.position]]
        for i, esc in enumerate(self.escs):
            # Hops and port links are physical: a silent ESC on the path delays the frame and
            # keeps port 1 of the slave before it open (DL status, DC receive times).
            esc.index = i
            esc.downstream = max(0, n - 1 - i)
            esc.set_last(i == n - 1)

    def process(self, frame: bytearray) -> bool:
        """Run every datagram of `frame` past the visible slaves; False: drop the frame."""
        if not self.path:
            return False
        if self.damage.shares and self.damage.spoils(self.path):
            return False  # lost, as the built-in master loses it
        self.frames += 1
        pd = False
        for dg in parse(frame):
            cmd = dg.cmd
            if Cmd.LRD <= cmd <= Cmd.LRW:
                pd = True
                self._logical(frame, dg)
            elif cmd in _AUTO:
                self._auto(frame, dg)
            elif cmd in _CONFIGURED:
                self._configured(frame, dg)
            elif Cmd.BRD <= cmd <= Cmd.BRW:
                self._broadcast(frame, dg)
        if pd:
            self.pd_frames += 1
        frame[6] |= 0x02  # like an ESC's port 0: source MAC marked locally administered
        return True

    def _logical(self, frame: bytearray, dg: Datagram) -> None:
        address = dg.logical_address
        cmd = dg.cmd
        wkc = get_wkc(frame, dg)
        for esc in self.visible:
            if esc.fmmus:
                wkc += esc.logical(cmd, address, frame, dg.offset, dg.length)
        set_wkc(frame, dg, wkc)
        if len(self.visible) < len(self.escs) and self._expected_wkc(dg) > wkc:
            self.wkc_errors += 1

    def _expected_wkc(self, dg: Datagram) -> int:
        """The WKC the whole line (vanished slaves included) would have given this datagram."""
        lo, hi = dg.logical_address, dg.logical_address + dg.length
        total = 0
        for esc in self.escs:
            kinds = 0
            for fm in esc.fmmus:
                if fm.log_start < hi and fm.log_end > lo:
                    kinds |= fm.kind
            if dg.cmd == Cmd.LRW:
                total += (1 if kinds & R.FMMU_READ else 0) + (2 if kinds & R.FMMU_WRITE else 0)
            elif kinds & (R.FMMU_READ if dg.cmd == Cmd.LRD else R.FMMU_WRITE):
                total += 1
        return total

    def _access(self, esc: Esc, cmd: int, frame: bytearray, dg: Datagram, kind: int) -> int:
        """kind 1 read, 2 write, 3 read-write: do it, return the WKC increment."""
        off, n = dg.offset, dg.length
        if kind == 1:
            frame[off:off + n] = esc.read(dg.ado, n)
            return 1
        if kind == 2:
            esc.write(dg.ado, bytes(frame[off:off + n]))
            return 1
        old = esc.read(dg.ado, n)
        esc.write(dg.ado, bytes(frame[off:off + n]))
        frame[off:off + n] = old
        return 3

    def _auto(self, frame: bytearray, dg: Datagram) -> None:
        target = (-dg.adp) & 0xFFFF
        wkc = get_wkc(frame, dg)
        if dg.cmd == Cmd.ARMW:
            wkc += self._read_multiple_write(frame, dg, lambda i, e: i == target)
        elif target < len(self.visible):
            wkc += self._access(self.visible[target], dg.cmd, frame, dg, _KIND[dg.cmd])
        set_wkc(frame, dg, wkc)
        set_adp(frame, dg, dg.adp + len(self.visible))

    def _configured(self, frame: bytearray, dg: Datagram) -> None:
        wkc = get_wkc(frame, dg)
        if dg.cmd == Cmd.FRMW:
            wkc += self._read_multiple_write(frame, dg, lambda i, e: e.station == dg.adp)
        else:
            kind = _KIND[dg.cmd]
            for esc in self.visible:
                if esc.station == dg.adp:
                    wkc += self._access(esc, dg.cmd, frame, dg, kind)
        set_wkc(frame, dg, wkc)

    def _read_multiple_write(self, frame: bytearray, dg: Datagram, is_reader) -> int:
        """ARMW / FRMW: the addressed slave reads into the frame, every other one writes what
        the frame then carries (how a master spreads the reference clock's time)."""
        if dg.ado == R.DC_SYSTEM_TIME and dg.length in (4, 8):
            return self._spread_time(frame, dg, is_reader)
        wkc = 0
        for i, esc in enumerate(self.visible):
            wkc += self._access(esc, dg.cmd, frame, dg, 1 if is_reader(i, esc) else 2)
        return wkc

    def _spread_time(self, frame: bytearray, dg: Datagram, is_reader) -> int:
        """The every-cycle drift datagram, kept cheap: the others only note the time they got
        (their 0x092C difference is worked out if a master ever reads it)."""
        off, n = dg.offset, dg.length
        if not self.visible:  # only silent slaves on the path: nobody takes the time
            return 0
        local = self.visible[0].clock.local_ns()
        for i, esc in enumerate(self.visible):
            if is_reader(i, esc):
                frame[off:off + n] = esc.read(dg.ado, n)
            elif esc.desc.dc_supported:
                esc.master_time = (int.from_bytes(frame[off:off + n], "little"), local)
        return len(self.visible)

    def _broadcast(self, frame: bytearray, dg: Datagram) -> None:
        off, n = dg.offset, dg.length
        wkc = get_wkc(frame, dg)
        cmd = dg.cmd
        for esc in self.visible:
            if cmd == Cmd.BWR:
                esc.write(dg.ado, bytes(frame[off:off + n]))
                wkc += 1
                continue
            mine = esc.read(dg.ado, n)
            if cmd == Cmd.BRW:
                esc.write(dg.ado, bytes(frame[off:off + n]))
                wkc += 3
            else:
                wkc += 1
            merged = int.from_bytes(frame[off:off + n], "little") | int.from_bytes(mine, "little")
            frame[off:off + n] = merged.to_bytes(n, "little")
        set_wkc(frame, dg, wkc)
        set_adp(frame, dg, dg.adp + len(self.visible))


_AUTO = frozenset({Cmd.APRD, Cmd.APWR, Cmd.APRW, Cmd.ARMW})
_CONFIGURED = frozenset({Cmd.FPRD, Cmd.FPWR, Cmd.FPRW, Cmd.FRMW})
_KIND = {Cmd.APRD: 1, Cmd.APWR: 2, Cmd.APRW: 3, Cmd.FPRD: 1, Cmd.FPWR: 2, Cmd.FPRW: 3}
