"""Long operator work off Blender's UI thread, with progress and Esc (the panel's Build and Compare).

Blender's `wm.progress_*` has no cancel, and an operator's `execute` blocks the UI until it
returns. So an operator started from the UI (`invoke`) prepares what needs bpy on the UI thread
(the export), hands the rest to a `BackgroundTask` thread, and runs modally: a timer event updates
the progress (window manager cursor and the status bar), Esc asks the task to stop, and when the
thread is done the operator finishes on the UI thread. Scripts calling the operator get `execute`,
which does the same work synchronously.

Tasks outlive neither the add-on nor the file they were started in: `stop_all` (unregister, and
load_pre when another file loads) cancels every running task, waits for its thread, and ends its
operator without letting it touch the scene (whose settings may be gone, or belong to another
file by the time the thread is done).
"""

from __future__ import annotations

import os
import threading
import time

#: How often (s) a modal operator looks at its task.
POLL_S = 0.1
#: Threads for work started from the UI: one core stays with Blender's UI thread (drawing the
#: window, which on a software OpenGL takes CPU too), or the UI stalls while the work runs.
UI_WORK_THREADS = max(1, (os.cpu_count() or 2) - 1)


class TaskCancelled(Exception):
    """The user pressed Esc; the work stopped at its next progress report."""


class BackgroundTask:
    """`work(task)` on a daemon thread. The work reports with `task.progress(fraction, text)`, which
    returns False once cancelled (for callbacks such as bvhlab.build's) and `task.check()`, which
    raises TaskCancelled then. Exceptions are kept for the UI thread (`error`), never lost."""

    def __init__(self, work):
        self.fraction, self.text = 0.0, ""
        self.result, self.error = None, None
        self._cancel = threading.Event()
        self._thread = threading.Thread(target=self._run, args=(work,), name="bvhlab task", daemon=True)
        self._thread.start()

    def _run(self, work) -> None:
        try:
            self.result = work(self)
        except BaseException as error:  # handed to the UI thread
            self.error = error

    def progress(self, fraction: float | None = None, text: str | None = None) -> bool:
        if fraction is not None:
            self.fraction = min(max(float(fraction), 0.0), 1.0)
        if text is not None:
            self.text = text
        return not self._cancel.is_set()

    def check(self) -> None:
        if self._cancel.is_set():
            raise TaskCancelled()

    def cancel(self) -> None:
        self._cancel.set()

    @property
    def cancelled(self) -> bool:
        return self._cancel.is_set()

    @property
    def done(self) -> bool:
        return not self._thread.is_alive()

    def wait(self, timeout: float | None = None) -> bool:
        """Joins the thread; True when it has ended."""
        self._thread.join(timeout)
        return self.done


#: Running tasks and the operator (a ModalTaskMixin) each belongs to, for stop_all.
_running: dict[BackgroundTask, object] = {}


def stop_all(wait_s: float = 10.0) -> int:
    """Cancel every running task, end its operator now (while the window manager and workspace it
    draws progress in still exist) and wait up to `wait_s` in all for the threads (the core's work
    polls its cancellation often: milliseconds). Returns how many tasks were stopped."""
    stopping = list(_running.items())
    _running.clear()
    for task, operator in stopping:
        task.cancel()
        try:
            operator._abandon()
        except ReferenceError:  # Blender freed the operator already (its window closed)
            pass
    deadline = time.monotonic() + wait_s
    for task, _ in stopping:
        task.wait(max(0.0, deadline - time.monotonic()))
    return len(stopping)


class ModalTaskMixin:
    """For operators: `start_task(context, work, label)` from `invoke`; implement
    `finish_task(context, task)` (UI thread, returns the operator's result set)."""

    _task: BackgroundTask | None = None
    _timer = None
    _label = ""
    _window_manager = None
    _workspace = None
    _abandoned = False
    _ended = False

    def start_task(self, context, work, label: str) -> set[str]:
        self._task, self._label = BackgroundTask(work), label
        window_manager = self._window_manager = context.window_manager
        self._workspace = context.workspace
        self._timer = window_manager.event_timer_add(POLL_S, window=context.window)
        window_manager.modal_handler_add(self)
        window_manager.progress_begin(0, 100)
        _running[self._task] = self
        self._show(context)
        return {"RUNNING_MODAL"}

    def modal(self, context, event):
        task = self._task
        if self._abandoned:  # stop_all ended it: nothing of the scene may be touched now
            self._remove_timer()
            return {"CANCELLED"}
        if event.type == "ESC" and event.value == "PRESS":
            task.cancel()
            self._show(context)
            return {"RUNNING_MODAL"}
        if event.type != "TIMER":  # any window timer: looking at the task is cheap
            return {"PASS_THROUGH"}
        if not task.done:
            self._show(context)
            return {"RUNNING_MODAL"}
        self._end()
        return self.finish_task(context, task)

    def _show(self, context) -> None:
        task = self._task
        context.window_manager.progress_update(int(task.fraction * 100))
        state = "cancelling…" if task.cancelled else f"{task.fraction:.0%}"
        text = f"{self._label}: {task.text} {state}" if task.text else f"{self._label} {state}"
        context.workspace.status_text_set(f"{text}   (Esc to cancel)")

    def _end(self, keep_timer: bool = False) -> None:
        """Stop drawing progress (once: stop_all may have ended the operator before)."""
        if self._ended:
            return
        self._ended = True
        _running.pop(self._task, None)
        if not keep_timer:
            self._remove_timer()
        self._window_manager.progress_end()
        self._workspace.status_text_set(None)

    def _remove_timer(self) -> None:
        if self._timer is not None:
            self._window_manager.event_timer_remove(self._timer)
            self._timer = None

    def cancel(self, context) -> None:
        """Blender ends the operator itself (another file loading, its window closing): its timer
        goes with it (it stayed, a window timer for the rest of the session: review)."""
        if self._task is not None:
            self._task.cancel()  # its result would come to no one
        self._end()
        self._remove_timer()  # also where stop_all abandoned it before (_end is done by then)
        self._abandoned = True

    def _abandon(self) -> None:
        """Ended by stop_all (the add-on disabled, another file loading): the progress goes now,
        the timer stays. Disabling the add-on frees the operator and leaves its handler in the
        window for Blender to drop at the window's next event, which the timer brings (without
        it, the handler stayed until some event came, and Blender 4.3 crashed when the add-on,
        enabled again, ran Build first: probe). The timer then stays, idle, until its window
        closes: removing it later from a bpy.app timer could touch a timer Blender freed with a
        closed window. Another file loading calls `cancel`, which removes it."""
        self._end(keep_timer=True)
        self._abandoned = True
