"""The Festo CPX-E-EC EtherCAT bus module and its CPX-E I/O modules (seed 002)."""
