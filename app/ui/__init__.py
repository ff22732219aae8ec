"""The viser dashboard of a rig (docs/dashboard.md)."""

from app.ui.dashboard import Dashboard

__all__ = ["Dashboard"]
