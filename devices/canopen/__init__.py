"""The servo drive's CANopen side as a pure, clock-driven model (seed 004 ch. 4).

``node.CanOpenNode`` wraps a :class:`~devices.servo.drive.ServoDrive`; the other modules hold
one concept each: NMT (``nmt``), heartbeat and guarding (``guarding``), PDOs (``pdo``),
emergencies (``emcy``), the communication objects (``comm_objects``), the dictionary a master
sees (``dictionary``), the SDO server shim (``sdo``), bus timing (``bus_timing``), the EDS
(``eds``) and the bus-monitor decoder (``decode``). docs/canopen.md describes the whole.
"""
