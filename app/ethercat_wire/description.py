"""What the wire process needs to know about one slave: identity, mailbox, SMs, PDOs.

Built by process A from the device models (their 0x1018 and PDO mapping) and handed to
process B, which turns it into an SII EEPROM image and register defaults; the ESI export
uses the same data plus what only a configurator needs (the PDOs not assigned by default,
whether their content may be edited, the modules of a slot). Plain frozen dataclasses so they
pickle across the spawn boundary.
"""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class PdoEntry:
    index: int
    sub: int
    bits: int
    name: str
    # ETG.2000 DataType name (SII: its code); "" for a gap or for a device whose configurator
    # types entries unsigned by bit length (the FastCAT, seed 000 §4)
    data_type: str = ""


@dataclass(frozen=True)
class Pdo:
    index: int
    name: str
    entries: tuple[PdoEntry, ...]
    mandatory: bool = False  # ESI Mandatory: a configurator may not leave it unassigned


@dataclass(frozen=True)
class SlotModule:
    """A module a configurator may put in the slave's slot (ETG.2000 Slots / Modules): a
    predefined set of PDOs assigned to SM2 / SM3 while the module is in the slot."""

    ident: int  # ModuleIdent
    type_name: str  # Module Type (TwinCAT's Slots tab, Module column)
    name: str  # Module Name (Description column)
    rx_pdos: tuple[Pdo, ...]
    tx_pdos: tuple[Pdo, ...]
    default: bool = False


@dataclass(frozen=True)
class SlotGroup:
    """One ETG.2000 Slot element of a modular device: ``min_instances`` .. ``max_instances``
    slots in a row, each taking a module of ``idents`` (``default``: the one a configurator
    puts there by itself, 0 for none)."""

    name: str
    min_instances: int
    max_instances: int
    idents: tuple[int, ...]
    default: int = 0


LCID_ENGLISH, LCID_RUSSIAN = 1033, 1049  # ESI LcId of a text (Windows locale ids)


@dataclass(frozen=True)
class DiagText:
    """The text of a diagnosis Text-ID (ETG.2000 DiagMessage): a configurator shows it for a
    0x10F3 history message carrying that Text-ID."""

    text_id: int
    texts: tuple[tuple[int, str], ...]  # (LcId, MessageText), 1033 English first


@dataclass(frozen=True)
class SyncManager:
    """SM0..SM3 as in SII category 41 (start, length, control, enable)."""

    start: int
    length: int
    control: int
    enable: int


@dataclass(frozen=True)
class SlaveDescription:
    device_id: str
    name: str  # SII string 1: the name SOEM shows
    vendor_id: int
    product_code: int
    revision: int
    serial: int
    group: str  # for the ESI
    order_code: str  # for the ESI
    # rx offset, rx size, tx offset, tx size (None: no mailbox)
    mailbox: tuple[int, int, int, int] | None
    coe_details: int  # SII GENERAL byte 5
    sync_managers: tuple[SyncManager, ...]
    rx_pdos: tuple[Pdo, ...]
    tx_pdos: tuple[Pdo, ...]
    dc_supported: bool
    # The slave runs DC-synchronous unless the master says otherwise: the ESI lists that OpMode
    # first, the one a configurator selects by default (the TRS-CAT, seed 001 §9.1.1)
    dc_default: bool = False
    # The ESI Desc of the OpMode without SYNC0 (AssignActivate 0), the text a configurator's DC
    # drop-down shows; the drive's is seed 004 ch. 5's TwinCAT screen's "SM-Synchron"
    sm_mode_desc: str = "FreeRun/SM-Synchron"
    fmmu_count: int = 3
    # Configured station alias (SII word 4, loaded into 0x0012): the CPX-E-EC's Explicit
    # Device ID in force (seed 002 Tab. 5), None at its switch 0 (the stored alias, 0 in a
    # fresh EEPROM); 0 for the others.
    station_alias: int | None = 0
    # For the ESI only (the SII and the wire use the assigned PDOs above): whether the master
    # may edit the PDOs' content (ESI Fixed), and the PDOs the slave has but does not assign
    # by default (listed without Sm, so a configurator can assign them).
    pdos_fixed: bool = True
    spare_rx_pdos: tuple[Pdo, ...] = ()
    spare_tx_pdos: tuple[Pdo, ...] = ()
    slot_name: str = ""  # the one slot of a non-modular slave with slot_modules
    slot_modules: tuple[SlotModule, ...] = ()
    # A modular device (ETG.2000): up to slot_count slots, each taking any of slot_modules; a
    # module's PDO indices grow by slot_pdo_increment per slot, its objects by
    # slot_index_increment; the ESI's Device then lists only the PDOs of device_pdos (the
    # slave's own), the modules' come with the modules. download_module_idents: the master
    # writes the configured modules to 0xF030 (ETG.5001).
    slot_count: int = 1
    # the Slot elements in slot order, where the slots do not all take the same modules (the
    # TRS-CAT's integrated module fixed in the first); empty: one Slot of slot_count
    slot_groups: tuple[SlotGroup, ...] = ()
    slot_pdo_increment: int = 0
    slot_index_increment: int = 0
    device_pdos: frozenset[int] | None = None  # None: every PDO is the device's
    download_module_idents: bool = False
    vendor_name: str = ""  # ESI Vendor Name, where the seed gives one
    # ESI Profile: the CoE profile number (0x1000's low word) and the texts of the 0x10F3
    # Text-IDs; written only for a slave with texts (the CPX-E-EC, seed 002 §2.5.2)
    profile_no: int = 0
    diag_texts: tuple[DiagText, ...] = ()
