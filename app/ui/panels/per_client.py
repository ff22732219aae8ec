"""The instructor's elements: built per instructor connection, so no other browser gets them.

viser sends a server-level widget, its value and every change of it to every browser, so a
fault picker or a table row naming an injected cause reached every trainee's page however
its style hid it (developer tools showed it). With a token (a classroom) such an element is
a part: built with ``client.gui`` for each connection that is the instructor, inside the
server-level container it belongs in and at the place it was registered (viser's ``order``).
On an open rig (no token: every browser is the instructor) a part is built once, server-level,
when registered: the dashboard looks and works as before (docs/classroom.md).
"""

from __future__ import annotations

import contextlib
import re
import threading
from collections.abc import Callable
from typing import Any, Generic, TypeVar

import viser
from viser._gui_api import _apply_default_order  # viser 1.1.1, pinned

from app.classroom.roles import Access, Role
from app.ui.style import INSTRUCTOR_CLASS

T = TypeVar("T")
ORDER_STEP = 1e-6  # a part's widgets sit between its reserved order and the next widget's


class _Ordered:
    """A ``GuiApi`` whose ``add_*`` calls take increasing orders from ``base`` on."""

    def __init__(self, gui: viser.GuiApi, base: float) -> None:
        self._gui, self._next = gui, base

    def __getattr__(self, name: str) -> Any:
        attr = getattr(self._gui, name)
        if not name.startswith("add_"):
            return attr

        def add(*args: Any, **kwargs: Any) -> Any:
            if kwargs.get("order") is None:
                self._next += ORDER_STEP
                kwargs["order"] = self._next
            return attr(*args, **kwargs)

        return add


class Part(Generic[T]):
    """What one ``build(gui)`` made, per instructor connection (or once, shared)."""

    def __init__(self, server: viser.ViserServer, build: Callable[[Any], T],
                 shared: bool) -> None:
        self._build = build
        self._server = server
        self._lock = threading.Lock()
        self._built: dict[int | None, T] = {}
        if shared:
            self._built[None] = build(server.gui)
            return
        gui = server.gui
        uuid = gui._get_container_uuid()
        self._container = None if uuid == "root" else gui._container_handle_from_uuid[uuid]
        self._order = float(_apply_default_order(None))

    def build_for(self, client: viser.ClientHandle) -> None:
        with self._lock:
            if client.client_id in self._built:
                return
        container = self._container if self._container is not None \
            else contextlib.nullcontext()
        with container:
            built = self._build(_Ordered(client.gui, self._order))
        with self._lock:
            self._built[client.client_id] = built

    def forget(self, client_id: int) -> None:
        with self._lock:
            self._built.pop(client_id, None)

    def of(self, client_id: int) -> T | None:
        """The copy built for ``client_id`` while its page is there (None: not built, gone,
        or an open rig's)."""
        return dict(self.items()).get(client_id)

    def items(self) -> list[tuple[int | None, T]]:
        """Every copy built so far whose page is still there, with its connection's id (None:
        an open rig's one).

        viser lets a leaving page go first (it leaves ``get_clients()``), then marks its
        widgets removed, then runs the disconnect callbacks (``Instructor._gone`` forgets the
        copy), which come late on a loaded machine. A copy updated in between was rebuilt on
        removed widgets: "Attempted to remove an already removed GuiCheckboxHandle", or a
        RuntimeError assigning a removed dropdown's options or HTML content, which ended that
        frame's update (tests/app/test_classroom_redraw.py,
        tests/app/test_instructor_html_gone.py)."""
        with self._lock:
            built = list(self._built.items())
        if all(client_id is None for client_id, _copy in built):
            return built
        present = self._server.get_clients()
        return [(client_id, copy) for client_id, copy in built
                if client_id is None or client_id in present]

    def each(self) -> list[T]:
        """Every copy built so far whose page is still there (update them all): see
        :meth:`items`."""
        return [copy for _client_id, copy in self.items()]


class ScenePart(Part[T]):
    """What one ``build(client)`` made for each instructor connection: scene nodes of its
    own (``client.scene``), which shadow the shared nodes of the same names on that page only
    (viser 1.1.1). Never built on an open rig, whose shared scene shows everything."""

    def __init__(self, server: viser.ViserServer,
                 build: Callable[[viser.ClientHandle], T]) -> None:
        self._build_scene = build
        self._server = server
        self._lock = threading.Lock()
        self._built: dict[int | None, T] = {}

    def build_for(self, client: viser.ClientHandle) -> None:
        with self._lock:
            if client.client_id in self._built:
                return
        built = self._build_scene(client)
        with self._lock:
            self._built[client.client_id] = built


class Instructor:
    """The dashboard's instructor parts and the connections they are built for."""

    def __init__(self, server: viser.ViserServer, access: Access) -> None:
        self.server = server
        self.access = access
        self.shared = access.open
        self._parts: list[Part[Any]] = []
        self._lock = threading.Lock()  # one connection's build at a time
        self.on_built: Callable[[], None] = lambda: None  # the dashboard redraws
        if not self.shared:
            server.on_client_disconnect(self._gone)

    def part(self, build: Callable[[Any], T]) -> Part[T]:
        """Register ``build(gui)``, called where the part's widgets go (inside its folder):
        built now on an open rig, else for each instructor connection (:meth:`promote`)."""
        part = Part(self.server, build, self.shared)
        self._parts.append(part)
        return part

    def scene_part(self, build: Callable[[viser.ClientHandle], T]) -> Part[T]:
        """Register ``build(client)`` for each instructor connection's own scene nodes
        (:class:`ScenePart`); nothing is built on an open rig."""
        part: Part[T] = ScenePart(self.server, build)
        if not self.shared:
            self._parts.append(part)
        return part

    def promote(self, client: viser.ClientHandle) -> None:
        """Build every part for ``client`` if it is the instructor (idempotent); nothing is
        kept for a page that closed meanwhile."""
        if self.shared or self.access.role(client.client_id) is not Role.INSTRUCTOR:
            return
        with self._lock:
            try:
                for part in self._parts:
                    part.build_for(client)
            except KeyError:
                if connected(self.server, client):
                    raise
            # Checked under the lock _gone takes: a page that leaves after this check is
            # forgotten by _gone, one that left before it by this.
            if not connected(self.server, client):
                self._forget(client)
                return
        self.on_built()

    def _gone(self, client: viser.ClientHandle) -> None:
        with self._lock:  # not while a build of it is under way (promote)
            self._forget(client)

    def _forget(self, client: viser.ClientHandle) -> None:
        for part in self._parts:
            part.forget(client.client_id)
        release_gone(client)


def connected(server: viser.ViserServer, client: viser.ClientHandle) -> bool:
    """False once viser has let ``client`` go: it leaves ``get_clients()`` before the
    disconnect callbacks run (viser 1.1.1, _viser.py)."""
    return client.client_id in server.get_clients()


def release_gone(client: viser.ClientHandle) -> None:
    """Unhook a gone client's elements from the server's containers. viser does it when the
    client leaves; what a build still made for it afterwards would stay in those containers
    (and a removal of one would cascade into the dead connection). Idempotent."""
    client.gui._release_cross_scope_nesting()


_ATTR = "_fieldrig_instructor"


def instructor_for(server: viser.ViserServer, access: Access | None = None) -> Instructor:
    """The server's :class:`Instructor`, made on the first call (with ``access``; an open
    one when none is given: a dashboard built without a classroom)."""
    found = getattr(server, _ATTR, None)
    if found is None:
        found = Instructor(server, access if access is not None else Access(None))
        setattr(server, _ATTR, found)
    return found


class InstructorHtml:
    """An HTML element for the instructor only (the injected causes under a state table)."""

    def __init__(self, instructor: Instructor) -> None:
        self._content = ""
        self._part = instructor.part(lambda gui: gui.add_html(self._content))

    def show_each(self, content_for: Callable[[int | None], str]) -> None:
        """Each instructor connection's copy the content of its own page's pick (the drive
        it shows); one built later starts from the last content of a new page's pick."""
        self._content = content_for(None)
        for client_id, handle in self._part.items():
            content = content_for(client_id)
            if handle.content != content:
                handle.content = content

    def show(self, content: str) -> None:
        # Every copy, even for content shown before: one built meanwhile (promote) started
        # from the content its build read and was not among the copies yet.
        self._content = content
        for handle in self._part.each():
            if handle.content != content:
                handle.content = content


_ROW = re.compile(rf'<tr class="{INSTRUCTOR_CLASS}">.*?</tr>', re.S)
_SPAN = re.compile(rf'<span class="{INSTRUCTOR_CLASS}" data-where="([^"]*)">(.*?)</span>', re.S)


def split_instructor(html: str, table_id: str) -> tuple[str, str]:
    """(what every browser may get, the instructor's table): the rows of
    :data:`app.ui.style.CAUSE_ROWS` and the spans of :data:`INSTRUCTOR_CLASS` (a CPX-E-EC
    module's wired but undiagnosed fault) go from the first into the second."""
    rows = _ROW.findall(html)
    spans = [f"{where}: {text.lstrip('; ')}" for where, text in _SPAN.findall(html)]
    public = _SPAN.sub("", _ROW.sub("", html))
    if spans:
        rows.append(f'<tr class="{INSTRUCTOR_CLASS}"><th>Not diagnosed</th>'
                    f"<td>{'; '.join(spans)}</td></tr>")
    if not rows:
        return public, ""
    return public, f'<table class="fr-kv" id="{table_id}">{"".join(rows)}</table>'


class RoleHtml:
    """A server-level HTML element whose content may hold the instructor's rows: on an open
    rig it shows them (one element, as before); with a token every browser gets the content
    without them and the instructor's connections a table of them right under it."""

    def __init__(self, server: viser.ViserServer, instructor: Instructor, content: str,
                 causes_id: str, own_causes: bool = True) -> None:
        """``own_causes=False``: with a token the instructor's rows are shown elsewhere (a
        part of the caller's with a picker of its own): here every browser gets the rest."""
        self._shared = instructor.shared
        self._causes_id = causes_id
        self.handle = server.gui.add_html(self._public(content))
        self._causes = None if self._shared or not own_causes else InstructorHtml(instructor)
        self._last = content
        self._last_causes = "" if self._shared else split_instructor(content, causes_id)[1]
        if self._causes is not None:
            self._causes.show(self._last_causes)

    def _public(self, content: str) -> str:
        return content if self._shared else split_instructor(content, self._causes_id)[0]

    def show(self, content: str) -> None:
        if content != self._last:
            self._last = content
            if self._shared:
                self.handle.content = content
                return
            public, self._last_causes = split_instructor(content, self._causes_id)
            if self.handle.content != public:
                self.handle.content = public
        if self._causes is not None:  # unchanged too: an instructor's copy may be new
            self._causes.show(self._last_causes)

    @property
    def content(self) -> str:
        """Everything, the instructor's rows included (tests)."""
        return self._last
