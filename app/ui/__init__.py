"""The viser dashboard of a rig (docs/dashboard.md)."""

from app.ui import viser_event

# Before any ViserServer builds its message buffers: their wake-up event is set from our
# threads, and viser 1.1.1's asyncio.Event is not thread-safe there (app/ui/viser_event.py).
viser_event.install()

from app.ui.dashboard import Dashboard  # noqa: E402

__all__ = ["Dashboard"]
