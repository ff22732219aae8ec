"""The servo drive as an EtherCAT CoE slave, a pure, clock-driven model (seed 004 ch. 5).

``drive_slave.DriveEcatSlave`` wraps a :class:`~devices.servo.drive.ServoDrive`; the other
modules hold one concept each: the ESM and its AL status codes (``esm``), the PDO assignment
0x1C12 / 0x1C13 and the slots (``assignment``), the process image (``process_image``), CSP
(``csp``), the CoE objects (``objects``), the mailbox (``mailbox``), emergencies
(``emergency``) and the LEDs (``leds``). docs/ethercat-coe.md describes the whole.
"""
