"""A run's second process: it draws the plots, and re-simulates the plan when it is free before the first process.

:func:`qsplan.planner.pipeline.run.run_plan` (``qsplan plan``, ``qsplan demo``) plans, exports and certifies in its
own process; the plots need none of that but the plan card's one verdict line.  :class:`Worker` starts one process when
the run starts (before the run takes its directory's lock, so that the worker holds no descriptor of it); it imports
matplotlib while the plan is searched (:func:`qsplan.planner.plotting.card.warm_up`) and is handed the plan once it is
exported (:meth:`Worker.start`).  It draws the plan card but its verdict
(:func:`qsplan.planner.plotting.card.draft_card`), then takes the re-simulations (:func:`replay_exported`) unless the run
has taken them first (whichever process is free first: the run once it has certified, the worker once the card is
drafted; each claims them in a shared value), then, with ``plots="all"``, draws the other figures and the animation,
all into the run's staging directory.  Once the certificate and the re-simulations are known, :meth:`Worker.finish`
sends the verdict and waits: the worker writes the verdict's lines onto the card
(:func:`~qsplan.planner.plotting.card.finish_card`) and answers with the files it wrote and the ones it could not draw.
The run publishes the files drawn; a figure not drawn is said, never a reason to withhold a certified plan
(:attr:`qsplan.planner.pipeline.run.PlanRun.undrawn`).  Re-simulations the worker could not finish are run again by
the run itself (the same computation: the same results, or the same error).

The worker ignores Ctrl-C (a terminal sends it to the whole process group: the run alone answers it) and ends with
the run: :meth:`Worker.stop` ends it before the staging directory is removed, on every exit, and on Linux the kernel
ends it if the run is killed.  The worker is forked (it starts at once, with what the run has loaded); where no process
can be forked (no ``fork`` on the platform, or the caller runs other threads), this process draws at
:meth:`Worker.finish` and re-simulates itself.  Two processes for two cores: one certifies, one draws (and re-simulates, when free first).
"""

from __future__ import annotations

import os
import pickle
import signal
import sys
import threading
from contextlib import contextmanager
from pathlib import Path

__all__ = ["ANIMATION_FILES", "PLAN_PLOTS", "PLOTS", "STOP_SECONDS", "Worker", "draw_plots", "plot_choice", "plot_files",
           "replay_exported", "start_early", "stop_early"]

#: What a run draws (``qsplan plan --plots``): the plan card alone (the default), every plot and the animation, or
#: nothing.
PLOTS = ("card", "all", "none")

#: The plots (``<name>.png``); ``plan_card`` is the one page for the operator, the others are drawn with
#: ``plots="all"``.
PLAN_PLOTS = ("plan_bands", "mode_timeline", "hand_snapshots", "plan_card")

#: The animation (:func:`qsplan.planner.plotting.animation.plan_animation`), drawn with ``plots="all"``: a GIF and a
#: self-contained HTML page with a slider.
ANIMATION_FILES = ("plan_animation.gif", "plan_animation.html")

#: Resolution (dots per inch) of the plots but the card (which is written at its own, for print).
_PLOT_DPI = 110

#: Seconds the worker is given to end after SIGTERM before it is killed (a worker drawing ends at once: nothing of
#: ours handles SIGTERM).
STOP_SECONDS = 5.0

#: Files the two processes hand each other in the staging directory, pickled (a pipe would block the writer until
#: the reader reads: a 200 kB plan while the worker still imports matplotlib, 2 MB of re-simulations while the run
#: certifies); never published.
_PLAN_FILE, _REPLAYS_FILE = ".worker-plan.pickle", ".worker-replays.pickle"

#: Who re-simulates the plan (the shared value both processes claim it in): nobody yet, the run, the worker.
_NOBODY, _RUN, _WORKER = 0, 1, 2

#: ``prctl`` option asking the kernel to signal this process when its parent dies (Linux, ``<sys/prctl.h>``).
_PR_SET_PDEATHSIG = 1

#: A worker the command line started before its own imports (:func:`start_early`), for the next :class:`Worker` to
#: take: ``[(process, connection, claim)]`` or empty.
_EARLY = []


def start_early(plots) -> None:
    """Start the second process of the run to come now, if it will draw ``plots`` (:func:`plot_choice`): the command
    line calls this first, so that the worker loads numpy and matplotlib while this process loads the planner; the
    next :class:`Worker` takes it (:func:`stop_early` ends it if none does)."""
    if plot_choice(plots) != "none" and not _EARLY:
        started = _start_worker()
        if started[0] is not None:
            _EARLY.append(started)


def stop_early() -> None:
    """End a worker :func:`start_early` started that no :class:`Worker` took (the run failed before it began)."""
    while _EARLY:
        proc, conn, _ = _EARLY.pop()
        with _sigint_held():
            _end(proc, conn)


def plot_choice(plots) -> str:
    """``plots`` as one of :data:`PLOTS`: ``True`` is ``"all"`` (every plot, as before the card was the default),
    ``False`` ``"none"``.

    Raises
    ------
    QsplanError
        Anything else.
    """
    if plots is True or plots is False:
        return "all" if plots else "none"
    if isinstance(plots, str) and plots in PLOTS:
        return plots
    from qsplan.mechanics.errors import QsplanError

    raise QsplanError(f"plots: expected one of {', '.join(map(repr, PLOTS))} (or True: 'all', False: 'none'); "
                      f"got {plots!r}")  # fmt: skip


def plot_files(plots) -> tuple:
    """The files a run drawing ``plots`` (:func:`plot_choice`) writes, in the order it lists them."""
    which = plot_choice(plots)
    if which == "none":
        return ()
    if which == "card":
        return ("plan_card.png",)
    return tuple(f"{n}.png" for n in PLAN_PLOTS) + ANIMATION_FILES


def replay_exported(plan, csv_path, n: int, seed: int, progress=None) -> list:
    """The exported file ``csv_path`` of ``plan`` re-simulated at ``n`` friction vectors of the task's interval
    (:func:`qsplan.planner.replay.replay.friction_samples`, seeded by ``seed``), in order."""
    from qsplan.planner.export.plan_files import read_plan_csv
    from qsplan.planner.replay.replay import friction_samples, replay_plan

    progress = progress or (lambda line: None)
    task = plan.task
    mus = friction_samples(task.mu_range, n, seed, shared=task.shared_mu, n_contacts=task.formation.n_contacts)
    columns = read_plan_csv(csv_path)
    out, scenes = [], {}  # the scenes along the plan do not depend on friction: built once for all replays
    for mu in mus:
        progress(f"re-simulating the exported plan at mu = {[round(float(m), 4) for m in mu]}")
        out.append(replay_plan(columns, task.hand, mu, scenes=scenes, formation=task.formation))
    return out


def draw_plots(plan, stage, plots, replays: int, stated, meanwhile=None) -> tuple:
    """Draw the plots ``plots`` (:func:`plot_files`) of ``plan`` into ``stage``; the plan card's verdict last.

    Parameters
    ----------
    plan : qsplan.planner.plan.results.Plan
    stage : pathlib.Path
        The directory written into.
    plots : str or bool
        :func:`plot_choice`.
    replays : int
        Re-simulations the verdict is expected to count (the card is drawn with room for it).
    stated : callable
        ``stated()`` -> ``(facts, followed)``: the certificate's facts
        (:func:`qsplan.planner.plotting.verdict.verdict_facts`) and each re-simulation's ``followed``, the card's verdict
        (:func:`~qsplan.planner.plotting.verdict.verdict_text`); called once the rest is drawn (the worker waits for it
        there).
    meanwhile : callable, optional
        Called once the card is drafted, before the other plots (the worker's re-simulations).

    Returns
    -------
    (names, undrawn)
        The files written, in :func:`plot_files`' order, and ``(file, reason)`` of each one not drawn (an error
        while drawing it: the others are drawn all the same).
    """
    from qsplan.planner.plotting.card import draft_card, finish_card
    from qsplan.planner.plotting.verdict import verdict_text

    files = plot_files(plots)
    done, undrawn = set(), []

    def attempt(names, draw):
        try:
            draw()
        except Exception as exc:  # noqa: BLE001 - any error of one figure: said, the others drawn
            undrawn.extend((n, _reason(exc)) for n in names)
            return
        done.update(names)

    draft = []
    if "plan_card.png" in files:
        attempt([], lambda: draft.append(draft_card(plan, replays)))
    if meanwhile is not None:
        meanwhile()
    if "plan_bands.png" in files:
        from qsplan.planner.plotting.plan import plan_snapshots_figure, plot_mode_timeline, plot_plan_bands
        from qsplan.planner.plotting.style import lay_out_once, save_figure

        def save(fig, name):
            lay_out_once(fig, _PLOT_DPI)
            save_figure(fig, stage / f"{name}.png", option="out_dir", dpi=_PLOT_DPI, tight=True)

        for name, figure in (("plan_bands", lambda: plot_plan_bands(plan)[0].get_figure(root=True)),
                             ("mode_timeline", lambda: plot_mode_timeline(plan).get_figure(root=True)),
                             ("hand_snapshots", lambda: plan_snapshots_figure(plan))):  # fmt: skip
            attempt([f"{name}.png"], lambda name=name, figure=figure: save(figure(), name))
    if ANIMATION_FILES[0] in files:
        from qsplan.planner.plotting.animation import plan_animation

        attempt(ANIMATION_FILES, lambda: plan_animation(plan, stage / ANIMATION_FILES[0], stage / ANIMATION_FILES[1]))
    if "plan_card.png" in files:
        line = verdict_text(*stated())
        if draft:
            attempt(["plan_card.png"], lambda: finish_card(draft[0], line, stage / "plan_card.png", option="out_dir"))
        else:  # the draft failed: once more whole, now that the verdict is known
            from qsplan.planner.plotting.card import CARD_DPI, plan_card
            from qsplan.planner.plotting.style import save_figure

            attempt(["plan_card.png"], lambda: save_figure(plan_card(plan, stated=line), stage / "plan_card.png",
                                                           option="out_dir", dpi=CARD_DPI, tight=False))  # fmt: skip
    reasons = dict(undrawn)  # the last reason of each file
    return [n for n in files if n in done], [(n, why) for n, why in reasons.items() if n not in done]


def _reason(exc) -> str:
    """An exception in one line."""
    text = " ".join(str(exc).split())
    return f"{type(exc).__name__}: {text}" if text else type(exc).__name__


class Worker:
    """The run's second process (see the module's docstring); a context manager that ends it on exit.

    Parameters
    ----------
    plots : str or bool
        :func:`plot_choice`; ``"none"`` starts nothing (the run re-simulates itself).
    """

    def __init__(self, plots):
        self.plots = plot_choice(plots)
        self._proc = self._conn = self._claim = self._job = None
        if self.plots != "none":
            early = _EARLY.pop() if _EARLY else None
            if early is not None and not early[0].is_alive():  # ended since (killed): a new one
                _end(*early[:2])
                early = None
            self._proc, self._conn, self._claim = early or _start_worker()

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.stop()
        return False

    @property
    def in_parallel(self) -> bool:
        """A second process draws (False: this process will, at :meth:`finish`)."""
        return self._proc is not None

    @property
    def pid(self) -> int | None:
        """The second process's id (None: none runs)."""
        return None if self._proc is None else self._proc.pid

    @property
    def replaying(self) -> str | None:
        """Who has taken the re-simulations: ``"run"`` (this process), ``"worker"``, or None (nobody yet)."""
        if self._claim is None:
            return None
        return {_RUN: "run", _WORKER: "worker"}.get(self._claim.value)

    def start(self, plan, stage, replays: int, seed: int) -> None:
        """Hand ``plan``, exported into ``stage``, to the worker: to draw, and to re-simulate ``replays`` times
        (:func:`replay_exported` with ``seed``) if it is free before this process."""
        self._job = (plan, Path(stage), int(replays), int(seed))
        if self._proc is None:
            return
        path = Path(stage) / _PLAN_FILE
        path.write_bytes(pickle.dumps(plan, protocol=pickle.HIGHEST_PROTOCOL))
        try:
            self._conn.send(("draw", str(path), str(stage), self.plots, int(replays), int(seed)))
        except OSError:  # the worker has ended already: finish() says so
            pass

    def replays(self, progress) -> list:
        """The plan re-simulated (:func:`replay_exported`): by this process, unless the worker has taken them, then
        its results (or, if it could not finish them, by this process after all)."""
        plan, stage, n, seed = self._job
        if n and self._claim is not None and not _take(self._claim, _RUN):
            progress(f"re-simulating the exported plan at {n} friction vectors (in the second process, meanwhile)")
            try:
                _, ok = self._conn.recv()
                if ok:
                    return pickle.loads((stage / _REPLAYS_FILE).read_bytes())
            except Exception:  # noqa: BLE001 - ended, or its file unreadable: re-simulated here, as it would have been
                pass
        return replay_exported(plan, stage / "plan.csv", n, seed, progress)

    def finish(self, certificate, followed) -> tuple:
        """Send the card's verdict: the facts of the plan's ``certificate``
        (:func:`qsplan.planner.plotting.verdict.verdict_facts`: plain numbers, loaded without the certifier) and each
        re-simulation's ``followed``; wait for the drawing.

        Returns
        -------
        (names, undrawn)
            As :func:`draw_plots`; a worker that ended without answering leaves every file undrawn, saying so.
        """
        from qsplan.planner.plotting.verdict import verdict_facts

        plan, stage, replays, _ = self._job
        stated = (verdict_facts(certificate), tuple(bool(f) for f in followed))
        if self._proc is None:
            return draw_plots(plan, stage, self.plots, replays, lambda: stated)
        try:
            self._conn.send(("verdict", stated))
            _, names, undrawn = self._conn.recv()
        except (EOFError, OSError):
            self._proc.join(STOP_SECONDS)
            code = self._proc.exitcode
            why = "the drawing process ended before drawing it" + (f" (exit status {code})" if code is not None else "")
            return [], [(n, why) for n in plot_files(self.plots)]
        return list(names), list(undrawn)

    def stop(self) -> None:
        """End the worker (at once: whatever it does is moot) and wait for it; idempotent.  A Ctrl-C meanwhile waits
        until it has ended (then raises as usual): no worker outlives a run and writes into its staging directory."""
        proc, conn = self._proc, self._conn
        self._proc = self._conn = None
        with _sigint_held():
            _end(proc, conn)


def _end(proc, conn) -> None:
    """Close ``conn``; end ``proc`` at once and wait for it (SIGTERM, then SIGKILL after :data:`STOP_SECONDS`)."""
    if conn is not None:
        conn.close()
    if proc is None:
        return
    if proc.is_alive():
        proc.terminate()
    proc.join(STOP_SECONDS)
    if proc.is_alive():
        proc.kill()
        proc.join()


def _take(claim, who) -> bool:
    """Claim the re-simulations for ``who``: True when nobody had."""
    with claim.get_lock():
        if claim.value != _NOBODY:
            return False
        claim.value = who
        return True


def _start_worker() -> tuple:
    """``(process, connection, claim)`` of a started worker, or Nones where none starts (this process does it all)."""
    import multiprocessing

    # fork starts in milliseconds with what this process loaded.  A process running other threads is never forked (the
    # child could inherit a lock one of them holds), and no fresh interpreter is started either (forkserver, spawn:
    # they import the caller's __main__ again, which runs an unguarded script's run once more): this process draws
    if "fork" not in multiprocessing.get_all_start_methods() or threading.active_count() != 1:
        return None, None, None
    ctx = multiprocessing.get_context("fork")
    for stream in (sys.stdout, sys.stderr):  # a forked child must not write what this process buffered
        try:
            stream.flush()
        except (OSError, ValueError, AttributeError):
            pass
    ours = theirs = None
    try:
        ours, theirs = ctx.Pipe()
        claim = ctx.Value("i", _NOBODY)
        with _sigint_held():
            proc = ctx.Process(target=_work, args=(theirs, claim, os.getpid()), name="qsplan-worker", daemon=True)
            proc.start()
    except (OSError, RuntimeError):  # no process to be had (limits, a sandbox): this process does it all
        for conn in (ours, theirs):
            if conn is not None:
                conn.close()
        return None, None, None
    theirs.close()  # this end is the worker's: its end closes when the worker ends, and recv() then says so
    return proc, ours, claim


@contextmanager
def _sigint_held():
    """SIGINT blocked in this thread meanwhile and delivered when the block ends: a worker started meanwhile starts
    with it blocked (fork and exec keep the mask), so no Ctrl-C reaches it before it ignores them."""
    if not hasattr(signal, "pthread_sigmask"):
        yield
        return
    old = signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGINT})
    try:
        yield
    finally:
        signal.pthread_sigmask(signal.SIG_SETMASK, old)


def _work(conn, claim, parent) -> None:
    """The worker: Ctrl-C ignored, ended with its ``parent`` (the run's pid); imports matplotlib, then does what it is
    sent."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    if hasattr(signal, "pthread_sigmask"):
        signal.pthread_sigmask(signal.SIG_UNBLOCK, {signal.SIGINT})
    _die_with_parent(parent)
    try:  # while the run plans: the drawing starts with matplotlib loaded
        from qsplan.planner.plotting.card import warm_up

        warm_up()
    except Exception:  # noqa: BLE001 - said when the drawing itself fails
        pass
    try:
        _, plan_path, stage, plots, replays, seed = conn.recv()
    except (EOFError, OSError):
        return
    stage = Path(stage)
    try:
        plan = pickle.loads(Path(plan_path).read_bytes())
    except Exception as exc:  # noqa: BLE001 - the run re-simulates itself; every plot said undrawn
        _replay(None, stage, replays, seed, conn, claim)
        _answer(conn, [], [(n, _reason(exc)) for n in plot_files(plots)])
        return

    def stated():
        _, value = conn.recv()  # EOFError: the run has ended; the worker with it
        return value

    try:
        names, undrawn = draw_plots(plan, stage, plots, replays, stated,
                                    meanwhile=lambda: _replay(plan, stage, replays, seed, conn, claim))  # fmt: skip
    except (EOFError, OSError):
        return
    _answer(conn, names, undrawn)


def _replay(plan, stage, n, seed, conn, claim) -> None:
    """The re-simulations, if the run has not taken them: written to the staging directory, then said (ok or not)."""
    if not n or not _take(claim, _WORKER):
        return
    ok = False
    if plan is not None:
        try:
            replays = replay_exported(plan, stage / "plan.csv", n, seed)
            (stage / _REPLAYS_FILE).write_bytes(pickle.dumps(replays, protocol=pickle.HIGHEST_PROTOCOL))
            ok = True
        except Exception:  # noqa: BLE001 - the run re-simulates itself and meets the same error there
            pass
    _answer(conn, ok)


def _answer(conn, *message) -> None:
    try:
        conn.send(("replays" if len(message) == 1 else "done", *message))
    except OSError:
        pass


def _die_with_parent(parent: int) -> None:
    """Linux: this process gets SIGTERM when ``parent``, the run that forked it, dies (a run killed, never shut down,
    leaves no worker drawing on); a parent that died between the fork and this request (the worker already handed to
    another parent, which sends no signal) is seen here, and the worker ends.  Elsewhere nothing is done (the worker
    ends at its next message: the pipe is closed)."""
    if not sys.platform.startswith("linux"):
        return
    import ctypes

    try:
        ctypes.CDLL(None, use_errno=True).prctl(_PR_SET_PDEATHSIG, int(signal.SIGTERM), 0, 0, 0)
    except (OSError, AttributeError):
        return
    if os.getppid() != parent:  # the parent died before the request: as if signalled
        os._exit(0)
