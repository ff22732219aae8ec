"""Messages between process A (the app, models) and process B (the wire, ESCs).

Each message is a tuple whose first item is one of the tags below, sent over a
`multiprocessing.connection.Connection`. Positions are 0-based line positions.
"""

from __future__ import annotations

# B -> A
READY = "ready"  # ("ready", iface)
AL_CONTROL = "al_control"  # ("al_control", pos, value): raw 0x0120 write
MAILBOX = "mailbox"  # ("mailbox", pos, data): complete SM0 message, header included
OUTPUTS = "outputs"  # ("outputs", pos, data): SM2 image after a master write changed it
# ("cycle", {pos: n_frames}): exchanges per slave (a silent slave: the frames that crossed
# its ESC), at most every 10 ms
CYCLE = "cycle"
DC = "dc"  # ("dc", pos, {"activation", "sync0_cycle_ns", "start_time_ns"})
# ("sm", pos, ((start, length, control, enabled), ...)): SM0.. registers after a master write
# changed them
SM = "sm"
# ("stats", {"frames", "lrw", "cycle_us", "wkc_errors", "lost_frames", "run"}), every 100 ms:
# counts in A's run (the last "damage" run; lrw since B started), cycle_us the mean
# process-data period of the last 100 ms (wire_process.Stats)
STATS = "stats"
ERROR = "error"  # ("error", text)
# ("esc_errors_write", pos, ado, length, seq): a master wrote into 0x0300-0x0313 (it clears
# counters; B cleared its copy already, A's model clears the same); seq: its number in the
# sequence of the esc_counts batches, acknowledged in A's esc_errors
ESC_ERRORS_WRITE = "esc_errors_write"
# ("esc_counts", seq, {pos: data}, run): what the damaged cables added to 0x0300-0x0313 (data
# as those registers) since the last batch, in A's run (the last "damage" run); seq numbers the
# batches from 1, at most every 10 ms
ESC_COUNTS = "esc_counts"
# ("station", pos, address): a master's write changed the configured station address (0x0010),
# the address it gives the slave on the line (the FastCAT compares it, seed 000 §6.19)
STATION = "station"

# A -> B
AL_STATUS = "al_status"  # ("al_status", pos, status, code): shown at 0x0130 / 0x0134
MAILBOX_REPLY = "mailbox_reply"  # ("mailbox_reply", pos, data): queued for SM1, in order
INPUTS = "inputs"  # ("inputs", pos, data): SM3 image
LINK = "link"  # ("link", pos, up): from pos on, slaves vanish from the wire
# ("silent", pos, on): the slave at pos is powered but does not answer (on) or answers again;
# its ESC passes frames on either way
SILENT = "silent"
ALIAS = "alias"  # ("alias", pos, value | None): a restart; None: the stored SII alias
# ("esc_errors", pos, data, seq): 0x0300-0x0313 as the model counts them, the esc_counts
# batches and esc_errors_write up to seq included
ESC_ERRORS = "esc_errors"
# ("damage", {cable: share}, seed, run): the damaged cables (share of the crossings spoiled),
# the seed of the generator that draws the crossings (devices/master/esc_errors.py) and the
# run (the rig's scenario loads, Rig.loads): a new run starts the crossings and counts afresh
DAMAGE = "damage"
STOP = "stop"  # ("stop",)

B_TO_A = (READY, AL_CONTROL, MAILBOX, OUTPUTS, CYCLE, DC, SM, STATS, ERROR, ESC_ERRORS_WRITE,
          ESC_COUNTS, STATION)
A_TO_B = (AL_STATUS, MAILBOX_REPLY, INPUTS, LINK, SILENT, ALIAS, ESC_ERRORS, DAMAGE, STOP)

CYCLE_REPORT_S = 0.010  # "cycle" at most this often
STATS_REPORT_S = 0.100  # "stats" this often
