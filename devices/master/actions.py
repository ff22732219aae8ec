"""The master's commands (seed 003 and FieldRig's fault injection), as data."""

from __future__ import annotations

from collections.abc import Mapping

from devices.device import Action, Param
from devices.master.dc import DC_FAULTS
from devices.master.links import TARGETS
from devices.master.log_styles import STYLES

MASTER_ACTIONS: Mapping[str, Action] = {a.name: a for a in (
    Action("resync", "Take every slave through INIT and back to the target state (a "
                     "resync resets the FastCAT alarms whose cause is gone, seed 000 §7)"),
    Action("set_target", "The state the master brings its slaves to",
           (Param("state", str, choices=TARGETS),)),
    Action("pull_cable", "Pull the cable that feeds line position N (0 = master -> first "
                         "slave): every slave from N on is cut off",
           (Param("cable", int, low=0),)),
    Action("plug_cable", "Plug the cable that feeds line position N again",
           (Param("cable", int, low=0),)),
    Action("power_slave", "Switch the slave at line position N on or off",
           (Param("position", int, low=0), Param("on", bool))),
    Action("lose_frames", "The next N cycles' frames are lost (communication error)",
           (Param("count", int, low=1, high=1_000_000),)),
    Action("damage_cable", "Damage cable N (its numbering as pull_cable): it spoils the given "
                           "percentage of the frames that cross it, either way; the ESCs "
                           "behind it count CRC errors (0x0300-0x030C), the master loses "
                           "those frames",
           (Param("cable", int, low=0), Param("percent", int, low=1, high=100))),
    Action("repair_cable", "Repair cable N: no new errors (the counters stay until cleared)",
           (Param("cable", int, low=0),)),
    Action("clear_esc_errors", "Clear the ESC error counters of the slave at line position N "
                               "(a master's write of 0x0300-0x0313)",
           (Param("position", int, low=0),)),
    Action("dc_fault", "Distributed clocks fault: drift, jitter over the sync window, "
                       "SYNC0 lost (seed 003 NOT_SYNCHRONIZED)",
           (Param("kind", str, choices=DC_FAULTS),)),
    Action("clear_dc_fault", "Remove the DC fault: the master synchronises again"),
    Action("set_log_style", "Render the log as TwinCAT, Sirio, Pegaso or AITracePrint "
                            "show it (seed 000 §7.1-§7.4)",
           (Param("style", str, choices=STYLES),)),
)}
