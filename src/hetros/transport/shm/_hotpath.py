"""The compiled hot path of this transport (``_cslot``), told the sample layout; None without it.

``send_cdr``, ``send_slot`` and ``take_cdr`` do the common case of ``Service.send_cdr``,
``Service.send`` and ``ShmReader._take_from`` and hand every other case back to them, so
both paths share one state and one set of rules; the conformance suite runs each
(``HETROS_PURE_PYTHON=1``). The state they read and write per message lives in slots of
``Service`` and ``_Port``, which ``bind_slots`` tells them where to find.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from ..._errors import TransportError
from ...msg import wanted
from ._credits import Credits
from ._iceoryx import assume_init, loan_slice
from ._sample import BORROW_LIMIT, CDR_BODY_AT, HEADER, MAPPED, MAX_SUBSCRIBER_SLOTS

# what send_cdr and send_slot return besides 0 (not handled) and 1 (sent): sent, but who to wake has changed
SENT_STALE_WAKES = 2

send_cdr: Callable[..., int] | None = None
send_slot: Callable[..., int] | None = None
take_cdr: Callable[..., Any] | None = None
try:  # built by pip where a C compiler is
    from . import _cslot
except ImportError:
    _cslot = None
if _cslot is not None and wanted():
    _cslot.configure(loan_slice, assume_init, HEADER.size, CDR_BODY_AT, Credits.HEAD, Credits.SLOT_WORDS,
                     MAX_SUBSCRIBER_SLOTS, BORROW_LIMIT, MAPPED.refresh)
    send_cdr, send_slot, take_cdr = _cslot.send_cdr, _cslot.send_slot, _cslot.take_cdr


# the slots the compiled path reads and writes in place, per class it is handed (``_cslot.c``'s
# bind list holds exactly these names; tests/unit/test_c_contracts.py checks both sides)
COMPILED_SLOTS: dict[type, tuple[str, ...]] = {}


def bind_slots(cls: type, names: tuple[str, ...]) -> None:
    """Let the compiled path read and write ``cls``'s slots ``names`` in place.

    A slot renamed on one side only would otherwise drop the class to the slow path without a
    word (or to an error deep in C): every name must be found, or the import fails here.
    """
    if _cslot is not None and wanted():
        bound = _cslot.bind_slots(cls)
        if bound != len(names):
            raise TransportError(
                f"{cls.__name__}: the compiled path found {bound} of its {len(names)} slots ({', '.join(names)}); "
                "a slot was renamed on one side: rename it in transport/shm/_cslot.c's bind list too")
    COMPILED_SLOTS[cls] = names


__all__ = ["COMPILED_SLOTS", "SENT_STALE_WAKES", "bind_slots", "send_cdr", "send_slot", "take_cdr"]
