"""Classroom logic without a UI: roles and access, hidden faults, exercises, scoring
(docs/classroom.md)."""
