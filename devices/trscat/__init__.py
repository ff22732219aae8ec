"""TRS-CAT EtherCAT remote I/O (seed 001): pure model. Behaviour and choices: docs/trscat.md."""
