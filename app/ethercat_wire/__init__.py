"""EtherCAT on the wire: the rig's slaves behind a raw 0x88A4 socket (issue 8).

Process B (`wire_process`) emulates the ESCs; process A (the app, `bridge`) owns the models.
"""
