"""The built-in EtherCAT master (seed 003), split by what each part holds:

- ``master``: :class:`EtherCatMaster` (commands, stepping, events and the log);
- ``actions``: its commands, as data;
- ``line``: cables, the slaves' power, lost frames, slaves lost and found;
- ``view``: its snapshot and the per-slave diagnostic structures;
- ``startup``: each slave's ESM start-up and supervision, init commands, identity;
- ``links``: the ``Slave`` protocol and the master's per-slave view and counters;
- ``dc``: the distributed-clock state machine (enum + transition table);
- ``log_styles``: the log's templates in the TwinCAT / Sirio / Pegaso / AITracePrint styles;
- ``hooks``: ECAT_Notify and ECAT_Resync callbacks;
- ``network``: the network description and mapping files, parsed from text.
"""

from devices.master.links import Slave, SlaveLink, next_state
from devices.master.master import (
    DEFAULT_EPOCH,
    FIRST_STATION_ADDRESS,
    LOG_LENGTH,
    STATE_CHECK_DELAY_US,
    STATE_TIMEOUT_US,
    TWINCAT_PORT,
    EtherCatMaster,
    twincat_timestamp,
)

__all__ = ["DEFAULT_EPOCH", "FIRST_STATION_ADDRESS", "LOG_LENGTH", "STATE_CHECK_DELAY_US",
           "STATE_TIMEOUT_US", "TWINCAT_PORT", "EtherCatMaster", "Slave", "SlaveLink",
           "next_state", "twincat_timestamp"]
