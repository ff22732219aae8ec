"""The servo drive of seed 004 (Modbus RTU, CANopen, EtherCAT CoE, Profinet fieldbus manual).

``ServoDrive`` is one state seen through the register view (R00..R133 and the keypad
parameters, what Modbus serves) and through the CiA 402 object dictionary ``drive.od`` (what
CANopen and CoE adapters serve). See docs/servo-drive.md.
"""

from devices.servo.config import DriveConfig
from devices.servo.drive import ServoDrive
from devices.servo.errors import AccessError

__all__ = ["AccessError", "DriveConfig", "ServoDrive"]
