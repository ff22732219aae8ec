"""The servo drive's Modbus RTU side (seed 004 ch.2): a pure PDU layer and a pymodbus server.

`app.modbus.pdu` turns one request PDU into drive calls and an outcome (reply, exception 02 or
silence); `app.modbus.server` frames it with pymodbus on TCP (MBAP or RTU framing) and hands
every request to the simulation thread. The rules and their seed sections: docs/modbus.md.
"""

from app.modbus.pdu import Exception02, Outcome, Reply, Silence, serve_line, serve_pdu

__all__ = ["Exception02", "Outcome", "Reply", "Silence", "serve_line", "serve_pdu"]
