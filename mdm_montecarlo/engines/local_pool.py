"""Local worker processes for run_many, stoppable at any moment.

concurrent.futures.ProcessPoolExecutor cannot be stopped safely: a worker killed while it
writes a result leaves the pool's manager thread waiting for the rest of the message, and
shutdown() (or the interpreter's exit) joins that thread forever. Here each worker has its own
pair of pipes and the parent has no helper thread: on Ctrl-C (or any error) the parent kills
the workers and closes its pipe ends; a pipe whose writer died reads as EOF, never blocks.
Workers ignore SIGINT (Ctrl-C reaches the whole process group; only the parent handles it).
"""

from __future__ import annotations

import gc
import multiprocessing
import signal
from collections.abc import Callable, Generator
from multiprocessing.connection import Connection, wait
from multiprocessing.process import BaseProcess
from typing import Any

Job = tuple[Any, ...]


def _serve(task: Callable[..., Any], jobs: Connection, results: Connection) -> None:
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    while (job := jobs.recv()) is not None:
        try:
            results.send(("ok", task(*job)))
        except Exception as exc:  # handed to the parent, which raises it
            results.send(("error", exc))


def imap_unordered(
    task: Callable[..., Any],
    jobs: list[Job],
    workers: int,
    started: Callable[[], object] | None = None,
) -> Generator[Any, None, None]:
    """``task(*job)`` for every job in ``workers`` processes, results as they finish.

    Jobs are handed out in the given order, one at a time per worker. ``started`` is called in
    this process once every worker has its first job: work of the caller's that the workers do
    not need can run then, not before they start. Closing the iterator early (an exception in
    the caller, KeyboardInterrupt) kills the workers at once.
    """
    ctx = multiprocessing.get_context()
    pending = list(reversed(jobs))
    procs: list[BaseProcess] = []
    links: dict[Connection, Connection] = {}
    """result reader -> job writer of the same worker."""
    try:
        for _ in range(min(workers, len(jobs))):
            job_read, job_write = ctx.Pipe(duplex=False)
            result_read, result_write = ctx.Pipe(duplex=False)
            proc = ctx.Process(target=_serve, args=(task, job_read, result_write), daemon=True)
            # Forked with this process's objects frozen, a worker's full collections skip them
            # (the imports: ~120 000 objects, ~0.1 s a pass, about one pass per worker).
            gc.freeze()
            try:
                proc.start()
            finally:
                gc.unfreeze()
            job_read.close()
            result_write.close()
            procs.append(proc)
            links[result_read] = job_write
            job_write.send(pending.pop())
        if started is not None:
            started()
        active = set(links)
        while active:
            for ready in wait(list(active)):
                assert isinstance(ready, Connection)
                try:
                    status, value = ready.recv()
                except EOFError:
                    raise RuntimeError("a worker process exited unexpectedly") from None
                if status == "error":
                    raise value
                if pending:
                    links[ready].send(pending.pop())
                else:
                    links[ready].send(None)
                    active.discard(ready)
                yield value
    finally:
        for worker in procs:
            if worker.is_alive():
                worker.kill()
        for worker in procs:
            worker.join(timeout=5)
        for reader, writer in links.items():
            reader.close()
            writer.close()
