"""The EtherCAT line in the dashboard: the 3D line with its cables, the master panel, the
slave panels, focus on click and on scenario ``Focus`` events (docs/dashboard.md)."""
