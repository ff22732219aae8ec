"""FastCAT modular EtherCAT I/O (seed 000): the coupler, its I/O modules and their catalog."""
