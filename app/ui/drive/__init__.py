"""The servo drives in the dashboard: tabs, controls, live plots, 3D axis (docs/dashboard.md)."""

from app.ui.drive.view import DriveView

__all__ = ["DriveView"]
