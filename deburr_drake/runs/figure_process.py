"""A run's figures drawn by a process forked before the run starts.

Importing matplotlib and drawing the five figures is about half of a short
``deburr-drake simulate``; the run itself needs neither. A process forked
at launch imports matplotlib while the parent imports pydrake, plans and
runs (on two cores the two overlap), then draws from the written logs.npz
when asked. What it returns is what drawing in the parent returns: the
paths, a failure said as one line (never raised), and the warnings of a
figure skipped, issued again in the parent. Where fork is not available,
or the process is gone, the parent draws itself.
"""

from __future__ import annotations

import multiprocessing
import os
import signal
import warnings

#: The figures in two halves of about equal drawing time (three 2-D
#: figures, two 3-D ones), drawn side by side by the process and a fork of
#: it.
_HALVES = (("fig08", "fig09", "fig10"), ("fig11_12",))


def draw_figures(logs_path, out, label, names=None):
    """(paths, failure): the run's figures (``names``, all by default) from
    logs.npz into ``out``; ``failure`` is one line (None when drawn), and
    no paths are returned with it."""
    import numpy as np

    from deburr_drake.runs import figures

    try:
        with np.load(logs_path) as logs:
            drawn = figures.make_figures(
                dict(logs),
                out,
                label=label,
                names=names or tuple(figures.FIGURE_NAMES),
            )
            return drawn, None
    except Exception as e:
        return [], f"{type(e).__name__}: {e}"


def _drawn(logs_path, out, label, names):
    """(paths, failure, warnings) of draw_figures, the warnings recorded
    to be issued again where the figures were asked for."""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        paths, failure = draw_figures(logs_path, out, label, names)
    said = [(str(w.message), w.category, w.filename, w.lineno) for w in caught]
    return paths, failure, said


def _draw_halves(logs_path, out, label):
    """_drawn for every figure, the second half drawn by a fork (by this
    process if the fork dies): the paths, the failure and the warnings
    those of drawing them in order."""
    ours, theirs = multiprocessing.Pipe()
    pid = os.fork()
    if pid == 0:
        try:
            ours.close()
            theirs.send(_drawn(logs_path, out, label, _HALVES[1]))
        finally:
            os._exit(0)
    theirs.close()
    first = _drawn(logs_path, out, label, _HALVES[0])
    try:
        second = ours.recv()
    except (EOFError, OSError):
        second = _drawn(logs_path, out, label, _HALVES[1])
    ours.close()
    os.waitpid(pid, 0)
    if first[1] is not None:
        return first
    paths, failure, said = second
    return (
        [] if failure else first[0] + paths,
        failure,
        first[2] + said,
    )


def _serve(connection):
    # Ctrl-C goes to the whole process group: the parent handles it (it
    # stops the run and still asks for the figures).
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    import deburr_drake.runs.figures  # noqa: F401  (the import to overlap)

    try:
        request = connection.recv()
    except (EOFError, OSError):
        return
    if request is not None:
        connection.send(_draw_halves(*request))


class FigureProcess:
    """The figure drawer, started at once; ``draw`` once, then ``close``
    (also a context manager)."""

    def __init__(self):
        self._process = self._connection = None
        self._drawn = False
        if "fork" not in multiprocessing.get_all_start_methods():
            return
        context = multiprocessing.get_context("fork")
        self._connection, theirs = context.Pipe()
        self._process = context.Process(
            target=_serve, args=(theirs,), name="figures", daemon=True
        )
        self._process.start()
        theirs.close()

    def draw(self, logs_path, out, label):
        """(paths, failure) as :func:`draw_figures`, drawn by the
        process (by this one where there is none)."""
        if self._process is not None:
            try:
                self._connection.send((logs_path, out, label))
                paths, failure, said = self._connection.recv()
                self._drawn = True
            except (EOFError, OSError):
                self.close()
            else:
                self.close()
                for message, category, filename, lineno in said:
                    warnings.warn_explicit(message, category, filename, lineno)
                return paths, failure
        return draw_figures(logs_path, out, label)

    def close(self):
        """Ends the process: it is done once it has drawn; before, it is
        stopped at once (it writes nothing until asked), so a command that
        refuses its input does not wait for matplotlib's import."""
        if self._process is None:
            return
        self._connection.close()
        if not self._drawn:
            self._process.kill()
        self._process.join(timeout=5.0)
        if self._process.is_alive():
            self._process.kill()
            self._process.join()
        self._process = self._connection = None

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()
