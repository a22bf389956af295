"""Running audit tasks: in this process (one job), on a local process pool, or on a Dask
cluster. Outcomes come back in completion order, as soon as each is known."""

import multiprocessing
import os
from collections.abc import Iterator, Sequence
from concurrent.futures import Future, ProcessPoolExecutor, as_completed

from auvdiag_cli.audit.worker import AuditOutcome, AuditTask, analyse
from auvdiag_errors import UsageError


def run_serial(tasks: Sequence[AuditTask]) -> Iterator[AuditOutcome]:
    for task in tasks:
        yield analyse(task)


def _lost(task: AuditTask, error: BaseException) -> AuditOutcome:
    """A worker that died (killed, out of memory) loses its log for this run only."""
    return AuditOutcome(task.log, None, error=f"{task.log}: worker failed: "
                        f"{type(error).__name__}: {error}", final=False)


def run_local(tasks: Sequence[AuditTask], jobs: int) -> Iterator[AuditOutcome]:
    # Parallelism comes from logs side by side: one math thread per worker, or N workers
    # each starting N BLAS threads oversubscribe the cores.
    for variable in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
        os.environ.setdefault(variable, "1")
    # spawn: fresh interpreters, no inherited threads or locks (the progress bar has some).
    executor = ProcessPoolExecutor(max_workers=jobs,
                                   mp_context=multiprocessing.get_context("spawn"))
    futures: dict[Future[AuditOutcome], AuditTask] = {executor.submit(analyse, task): task
                                                      for task in tasks}
    try:
        for future in as_completed(futures):
            try:
                yield future.result()
            except Exception as error:
                yield _lost(futures[future], error)
    finally:
        executor.shutdown(wait=False, cancel_futures=True)


def run_dask(tasks: Sequence[AuditTask], address: str) -> Iterator[AuditOutcome]:
    """On an existing cluster; its workers need auvdiag installed and the logs at the same
    paths (a shared filesystem). Results come back here and are written by this process."""
    try:
        from distributed import Client
        from distributed import as_completed as dask_completed
    except ImportError:
        raise UsageError("--scheduler needs Dask: pip install 'auvdiag[dask]'") from None
    try:
        client = Client(address, timeout="10s")
    except (OSError, TimeoutError) as error:
        raise UsageError(f"cannot reach the Dask scheduler at {address}: {error}") from None
    try:
        futures = client.map(analyse, list(tasks), pure=False)
        owner = {future.key: task for future, task in zip(futures, tasks, strict=True)}
        # A worker keeps a result while a future here refers to it: hand each one back once
        # fetched, or every log's time histories stay on the workers to the end.
        completed = dask_completed(futures)
        del futures
        for future in completed:
            try:
                yield future.result()
            except Exception as error:
                yield _lost(owner[future.key], error)
            finally:
                future.release()
    finally:
        client.close()


def run_tasks(tasks: Sequence[AuditTask], jobs: int, scheduler: str | None
              ) -> Iterator[AuditOutcome]:
    if not tasks:
        return iter(())
    if scheduler is not None:
        return run_dask(tasks, scheduler)
    if jobs <= 1 or len(tasks) == 1:
        return run_serial(tasks)
    return run_local(tasks, min(jobs, len(tasks)))
