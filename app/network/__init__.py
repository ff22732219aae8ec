"""Network description and mapping files of the EtherCAT master (seed 003): reading them for a
rig file (``files``) and generating them from a rig (``generate``)."""
