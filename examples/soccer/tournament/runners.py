"""Playing a tournament's matches: a local process pool, or the tasks of a Ray cluster.

Both runners play :func:`~.match.play` on every :class:`~.match.MatchSpec` and hand each result
to ``on_result`` as soon as it arrives (in completion order; the report sorts by match number).
The two programs are pickled once and shipped to each worker (pool initializer, Ray object
store), so workers never compile and need no access to the behavior folders.

Ctrl+C: the runner stops handing out matches, asks running ones to stop (the local pool through
a shared event that the matches poll every simulated second; Ray by cancelling its tasks) and
re-raises ``KeyboardInterrupt`` once the workers are gone, so the caller reports what finished.

Ray is an optional extra (``pip install 'xabsl-studio[ray]'``), imported only by :func:`run_ray`.
"""

from __future__ import annotations

import multiprocessing
import os
import signal
import socket
from collections.abc import Callable, Sequence
from concurrent.futures import FIRST_COMPLETED, Future, ProcessPoolExecutor, wait
from pathlib import Path
from typing import Any

from xabsl_studio.engine.cli import UsageError
from xabsl_studio.engine.ir.model import Program
from xabsl_studio.examples.soccer.tournament.match import MatchSpec, play

OnResult = Callable[[dict[str, Any]], None]

# -- local process pool ---------------------------------------------------------------------------

#: HOME's and AWAY's source files, kept in the recordings of recorded matches (None: not kept)
Sources = tuple[dict[str, Any] | None, dict[str, Any] | None]

_programs: tuple[Program, Program] | None = None
_sources: Sources = (None, None)
_stop: Any = None


def _init_worker(programs: tuple[Program, Program], stop: Any, sources: Sources) -> None:
    global _programs, _stop, _sources
    # Ctrl+C goes to the whole process group: the parent decides, workers finish or stop on ``stop``.
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    _programs, _stop, _sources = programs, stop, sources


def _play_in_worker(spec: MatchSpec) -> dict[str, Any]:
    assert _programs is not None
    return play(spec, *_programs, stop=_stop.is_set, sources=_sources)


def _failure(spec: MatchSpec, error: str) -> dict[str, Any]:
    return {
        "index": spec.index,
        "seed": spec.seed,
        "home_colour": "blue" if spec.home_blue else "red",
        "ok": False,
        "error": error,
    }


def run_local(
    specs: Sequence[MatchSpec],
    programs: tuple[Program, Program],
    jobs: int,
    on_result: OnResult,
    sources: Sources = (None, None),
) -> None:
    """Play ``specs`` in ``jobs`` worker processes (forkserver: no threads are forked)."""
    context = multiprocessing.get_context("forkserver")
    context.set_forkserver_preload(["xabsl_studio.examples.soccer.tournament.match"])
    stop = context.Event()
    executor = ProcessPoolExecutor(
        max_workers=max(1, min(jobs, len(specs))),
        mp_context=context,
        initializer=_init_worker,
        initargs=(programs, stop, sources),
    )
    futures: dict[Future[dict[str, Any]], MatchSpec] = {}
    try:
        futures = {executor.submit(_play_in_worker, spec): spec for spec in specs}
        pending = set(futures)
        while pending:
            done, pending = wait(pending, timeout=0.5, return_when=FIRST_COMPLETED)
            for future in sorted(done, key=lambda f: futures[f].index):
                error = future.exception()
                if error is None:
                    on_result(future.result())
                else:  # the worker process died (a crash, out of memory): say so for this match
                    on_result(_failure(futures[future], f"{type(error).__name__}: {error}"))
    except KeyboardInterrupt:
        stop.set()
        executor.shutdown(wait=True, cancel_futures=True)
        raise
    finally:
        executor.shutdown(wait=True, cancel_futures=True)


# -- Ray ------------------------------------------------------------------------------------------


def _import_ray() -> Any:
    try:
        import ray
    except ImportError as error:
        raise UsageError(
            "--ray needs Ray, an optional extra: pip install 'xabsl-studio[ray]' (or pip install 'ray>=2.9')"
        ) from error
    return ray


def _code_modules() -> list[str]:
    """The package a Ray worker elsewhere needs: this checkout's ``xabsl_studio``."""
    import xabsl_studio

    return [str(Path(xabsl_studio.__file__).parent)]


#: Where ``ray start`` notes the address of the cluster it started on this machine.
RAY_CURRENT_CLUSTER = Path("/tmp/ray/ray_current_cluster")
#: Where ``ray start --head`` (Ray 2.59 and later) keeps the token of the cluster's authentication.
RAY_TOKEN_FILE = Path("~/.ray/auth_token")


def _ray_token_found(environ: dict[str, str] | os._Environ[str] = os.environ) -> bool:
    """Whether this machine has a Ray authentication token (Ray's own sources, in its order)."""
    if environ.get("RAY_AUTH_TOKEN"):
        return True
    path = environ.get("RAY_AUTH_TOKEN_PATH")
    return Path(path).expanduser().is_file() if path else RAY_TOKEN_FILE.expanduser().is_file()


def _authenticate_to_ray(environ: dict[str, str] | os._Environ[str] = os.environ) -> bool:
    """Turn Ray's token authentication on for a driver joining a cluster, when a token is here.

    A head started with ``ray start --head`` (Ray 2.59 and later) requires the token, but a driver
    that joins it by address sends it only with ``RAY_AUTH_MODE=token``, and is otherwise refused
    after a minute of retries ("Authentication token is missing or incorrect"). Ray reads the
    mode when it is imported: call this first. An explicit ``RAY_AUTH_MODE`` (``disabled``
    included) is the user's and is kept. Returns whether a token is available.
    """
    found = _ray_token_found(environ)
    if found and "RAY_AUTH_MODE" not in environ:
        environ["RAY_AUTH_MODE"] = "token"
    return found


def _check_reachable(address: str) -> None:
    """Fail fast when no Ray cluster answers at ``address`` (``auto`` or ``HOST:PORT``).

    Ray itself retries for minutes before it gives up on an address nothing listens at.

    Raises:
        UsageError: no cluster address is known, or nothing listens there.
    """
    if address.startswith("ray://"):
        return  # a Ray client server: Ray reports that one itself
    if address == "auto":
        found = os.environ.get("RAY_ADDRESS", "")
        if not found and RAY_CURRENT_CLUSTER.is_file():
            found = RAY_CURRENT_CLUSTER.read_text(encoding="utf-8").strip()
        if not found:
            raise UsageError("--ray auto: no Ray cluster started on this machine (start one: ray start --head)")
        address = found
    host, colon, port = address.rpartition(":")
    if not colon or not port.isdigit():
        raise UsageError(f"--ray {address}: expected HOST:PORT, auto or local")
    try:
        socket.create_connection((host, int(port)), timeout=3.0).close()
    except OSError as error:
        raise UsageError(
            f"--ray: no Ray cluster answers at {address} ({error.strerror or error}); start one: ray start --head"
        ) from None


def run_ray(
    specs: Sequence[MatchSpec],
    programs: tuple[Program, Program],
    address: str,
    jobs: int | None,
    on_result: OnResult,
    sources: Sources = (None, None),
) -> int:
    """Play ``specs`` as Ray tasks (one CPU each); returns the CPUs of the cluster.

    Args:
        specs: the matches.
        programs: HOME's and AWAY's programs.
        address: ``local`` starts a Ray instance in this process (``jobs`` CPUs); ``auto`` joins
            the cluster running on this machine (``ray start --head``); anything else is a
            cluster address (``HOST:6379``, ``ray://HOST:10001``). Joined clusters get this
            checkout's ``xabsl_studio`` package shipped (``py_modules``), so the
            nodes need only the dependencies (pymunk, numpy, ...), not the sources.
        jobs: CPUs of a ``local`` instance (None: all cores); a joined cluster has its own.
        on_result: called with each match's result as it arrives.
        sources: the versions' source files for recorded matches (a recording is written by the
            node that plays the match, where its ``MatchSpec.record`` points).
    """
    token = False
    if address != "local":
        _check_reachable(address)
        token = _authenticate_to_ray()  # before Ray is imported: it reads its mode then
    ray = _import_ray()
    import logging

    if address == "local":
        # address="local": always a new instance, never a cluster an earlier `ray start` left behind
        ray.init(
            address="local", num_cpus=jobs, include_dashboard=False, logging_level=logging.WARNING, log_to_driver=False
        )
    else:
        try:
            ray.init(
                address=address,
                runtime_env={"py_modules": _code_modules()},
                logging_level=logging.WARNING,
                log_to_driver=False,
            )
        except ConnectionError as error:
            hint = (
                ""
                if token
                else " (a cluster with token authentication, the default of `ray start` since Ray 2.59, needs its "
                "token here: run `ray get-auth-token` on the head and put it in ~/.ray/auth_token or RAY_AUTH_TOKEN)"
            )
            raise UsageError(f"--ray {address}: {error}{hint}") from error
    refs: dict[Any, MatchSpec] = {}
    try:
        cpus = int(ray.cluster_resources().get("CPU", 0))
        remote_play = ray.remote(num_cpus=1, max_retries=0)(play)
        home, away = (ray.put(p) for p in programs)
        kept = ray.put(sources)
        refs = {remote_play.remote(spec, home, away, None, kept): spec for spec in specs}
        pending = list(refs)
        while pending:
            done, pending = ray.wait(pending, num_returns=1, timeout=0.5)
            for ref in done:
                try:
                    on_result(ray.get(ref))
                except Exception as error:  # the task's worker died, or Ray itself failed
                    on_result(_failure(refs[ref], f"{type(error).__name__}: {error}"))
        return cpus
    except KeyboardInterrupt:
        for ref in refs:
            ray.cancel(ref, force=True)
        raise
    finally:
        ray.shutdown()
