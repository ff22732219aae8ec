"""bench/wire.py's stand-in for the ESM: it must end quietly when the wire process goes away."""

import multiprocessing
import threading

from app.ethercat_wire import messages
from bench.wire import answer_al_control


def test_the_al_control_answerer_ends_when_the_wire_process_has_gone() -> None:
    # The bench sets `stop` and sends STOP; the wire process then exits and closes its end,
    # which wakes a pending poll() with EOF before the loop sees `stop`.
    ours, theirs = multiprocessing.Pipe()
    theirs.close()
    answer_al_control(ours, threading.Event())  # returns, no EOFError


def test_the_al_control_answerer_grants_the_requested_state() -> None:
    ours, theirs = multiprocessing.Pipe()
    stop = threading.Event()
    answerer = threading.Thread(target=answer_al_control, args=(ours, stop), daemon=True)
    answerer.start()
    try:
        theirs.send((messages.AL_CONTROL, 3, 0x18))  # slave 3: OP with the acknowledge bit
        assert theirs.poll(5)
        assert theirs.recv() == (messages.AL_STATUS, 3, 0x08, 0)
    finally:
        stop.set()
        answerer.join(5)
