"""A Dask client for the simulators' and the library's fan-out: given, or connected to a
scheduler address within :data:`SCHEDULER_TIMEOUT_S` (a thread waits, so that an address
that never answers costs seconds, not Dask's own minutes).

>>> _client(None, None)
(None, False)
"""

from __future__ import annotations

#: Seconds to wait for a Dask scheduler given by address.
SCHEDULER_TIMEOUT_S = 10.0


def _client(client, scheduler):
    """(client, whether this call made it): the given client, a new one connected to
    ``scheduler``, or (None, False) for a local run."""
    if client is not None and scheduler is not None:
        raise ValueError("give either client or scheduler, not both")
    if client is None and scheduler is None:
        return None, False
    try:
        from dask.distributed import Client
    except ImportError as exc:  # optional dependency
        raise ImportError(
            "running on a cluster needs dask.distributed: pip install 'dask[distributed]' (or openpbr-diffuse[dask])"
        ) from exc
    if client is not None:
        return client, False
    try:
        import threading

        # Client(timeout=) bounds the TCP connect, not the handshake with a silent peer:
        # connect in a daemon thread and give up after the same time
        box: list = []

        def connect():
            try:
                box.append(Client(scheduler, timeout=SCHEDULER_TIMEOUT_S))
            except BaseException as e:  # noqa: BLE001 -- handed to the caller
                box.append(e)

        th = threading.Thread(target=connect, daemon=True, name="dask-connect")
        th.start()
        th.join(SCHEDULER_TIMEOUT_S + 1.0)
        if not box:
            raise TimeoutError("no answer")
        if isinstance(box[0], BaseException):
            raise box[0]
        return box[0], True
    except (OSError, TimeoutError, MemoryError, ValueError, TypeError) as exc:
        # a silent port times out; a service that is not a Dask scheduler may answer garbage
        # (read as an absurd frame length: MemoryError) or close the connection
        raise ConnectionError(
            f"scheduler {scheduler}: no Dask scheduler answered within {SCHEDULER_TIMEOUT_S:g} s ({type(exc).__name__})"
        ) from None


__all__ = ["SCHEDULER_TIMEOUT_S"]
