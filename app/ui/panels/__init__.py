"""The dashboard's GUI panels: control, state, event log, object dictionary."""
