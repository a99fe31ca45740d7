"""Background work that never freezes Blender's UI.

A :class:`Task` runs a Blender-free function on a worker thread.  The worker
never touches ``bpy``: it reports progress into plain attributes and polls a
cancel flag.  A ``bpy.app.timers`` callback on the main thread copies progress
into the window manager (panel and status-bar bars), redraws, and when the
worker ends hands its result (or error) to the task's main-thread callbacks,
which create Blender data.  One task runs at a time.

In background mode (``blender -b``, the ``bpy`` module) there is no event loop
to fire timers, so :func:`start` with ``blocking=True`` runs the work and its
callbacks inline instead.

Opening another file (File > New, Open, Revert) cancels a task that still runs and drops it with its callbacks:
the data they would fill belongs to the file being closed, and Blender drops the task's timer with that file.
"""
from __future__ import annotations

import threading
import time
import traceback
from typing import Callable

import bpy
from bpy.app.handlers import persistent
from bpy.props import BoolProperty

from .. import backend

__all__ = ["Task", "TaskOperator", "start", "current", "idle", "cancel", "wait", "shutdown", "attach", "detach",
           "POLL_SECONDS", "CLOSE_SECONDS"]

POLL_SECONDS = 0.1
#: how long opening another file waits for a cancelled task's worker to stop (a neural step, a chunk of a bake)
CLOSE_SECONDS = 2.0
_current: "Task | None" = None


class Task:
    """work(progress, cancel) -> result, run off the main thread.

    on_done(result) and on_error(message) run on the main thread.
    """

    def __init__(self, label: str, work: Callable, on_done: Callable | None = None,
                 on_error: Callable | None = None, threads: int = 0):
        self.label = label
        self.work = work
        self.on_done = on_done
        self.on_error = on_error
        self.threads = threads
        self.progress = 0.0
        self.status = "running"  # running | done | failed | cancelled
        self.message = ""
        self.error: Exception | None = None     # what failed the work, for the operator to name in its terms
        self.result = None
        self.started = time.perf_counter()
        self._cancel = threading.Event()
        #: set at the first progress report (scripts and tests wait on it instead of spinning)
        self.progressed = threading.Event()
        self._thread: threading.Thread | None = None
        self._finished = False
        # the timer callback, bound once: bpy.app.timers compares callbacks by identity and a fresh bound
        # method (task.poll) is never "registered", so it could not be unregistered (a timer left behind made
        # Blender 4.5 hang at exit)
        self.timer = self.poll

    # -- worker side (no bpy) ----------------------------------------------------------
    def _report(self, fraction: float) -> None:
        self.progress = min(1.0, max(self.progress, float(fraction)))
        self.progressed.set()

    def cancelled(self) -> bool:
        return self._cancel.is_set()

    def _run(self) -> None:
        try:
            if self.threads > 0:
                try:
                    import numba

                    numba.set_num_threads(min(self.threads, numba.config.NUMBA_NUM_THREADS))
                except ImportError:
                    pass
            self.result = self.work(self._report, self.cancelled)
            self.status = "cancelled" if self._cancel.is_set() else "done"
        except backend.Cancelled:
            self.status = "cancelled"
        except (backend.SettingError, OSError, ValueError, RuntimeError) as exc:
            self.status, self.message, self.error = "failed", str(exc), exc
        except Exception as exc:  # an engine bug: keep the trace for the console, one line for the UI
            traceback.print_exc()
            self.status, self.message = "failed", f"{type(exc).__name__}: {exc}"

    # -- main thread -------------------------------------------------------------------
    def cancel(self) -> None:
        self._cancel.set()

    @property
    def running(self) -> bool:
        return not self._finished

    def finish(self) -> None:
        """Main thread: run the callbacks once the worker is over."""
        global _current
        if self._finished:
            return
        self._finished = True
        if _current is self:
            _current = None
        if self.status == "done" and self.on_done is not None:
            try:
                self.on_done(self.result)
            except backend.SettingError as exc:      # the data changed while the work ran (a mesh edited)
                self.status, self.message, self.error = "failed", str(exc), exc
            except Exception as exc:  # turning files into Blender data failed
                traceback.print_exc()
                self.status, self.message = "failed", f"{type(exc).__name__}: {exc}"
        if self.status == "failed" and self.on_error is not None:
            self.on_error(self.message)
        _redraw()

    def poll(self):
        """bpy.app.timers callback: seconds until the next poll, or None when over."""
        if self._thread is not None and self._thread.is_alive():
            _redraw()
            return POLL_SECONDS
        self.finish()
        return None


def _redraw() -> None:
    wm = getattr(bpy.context, "window_manager", None)
    if wm is None:
        return
    for window in wm.windows:
        for area in window.screen.areas:
            if area.type in ("VIEW_3D", "NODE_EDITOR", "PROPERTIES", "STATUSBAR"):
                area.tag_redraw()


def current() -> "Task | None":
    return _current


def idle(cls) -> bool:
    """An operator's poll: True while no task runs; else False, and the disabled button's tooltip says which task
    holds OmniNoise (Blender's ``poll_message_set``)."""
    task = current()
    if task is None:
        return True
    cls.poll_message_set(f"OmniNoise is busy with {task.label}: wait for it, or press Esc to cancel it")
    return False


def start(task: Task, blocking: bool = False) -> Task:
    """Run ``task``: on a thread polled by a timer, or inline when ``blocking``."""
    global _current
    if _current is not None and _current.running:
        raise RuntimeError(f"OmniNoise is busy with {_current.label!r}; wait or cancel it first")
    _current = task
    if blocking:
        task._run()
        task.finish()
        return task
    task._thread = threading.Thread(target=task._run, name=f"omninoise: {task.label}", daemon=True)
    task._thread.start()
    bpy.app.timers.register(task.timer, first_interval=POLL_SECONDS)
    return task


def cancel() -> bool:
    """Ask the running task to stop; True if there was one."""
    if _current is None or not _current.running:
        return False
    _current.cancel()
    return True


def shutdown(timeout: float = 10.0) -> None:
    """Leave nothing running (the add-on is being disabled, another file opens): cancel the task, wait up to
    ``timeout`` seconds for its worker thread, drop its timer.  Its callbacks do not run: the classes or the data
    they would use are going away."""
    global _current
    task = _current
    if task is None:
        return
    task.cancel()
    if task._thread is not None:
        task._thread.join(timeout)
    if bpy.app.timers.is_registered(task.timer):
        bpy.app.timers.unregister(task.timer)
    if task.status == "running":
        task.status = "cancelled"
    task._finished = True
    _current = None


@persistent
def _file_closing(*_args) -> None:
    """``load_pre`` handler: the running task cancelled and dropped (:func:`shutdown`) before another file opens.
    Left running, its timer (dropped by Blender with the file) never finished it, and OmniNoise stayed busy with it
    until Blender was restarted."""
    task = _current
    if task is not None and task.running:
        print(f"OmniNoise: {task.label} cancelled: another file was opened")
    shutdown(CLOSE_SECONDS)


def attach() -> None:
    """What register() adds for tasks: the handler that drops a running task when another file opens."""
    if _file_closing not in bpy.app.handlers.load_pre:
        bpy.app.handlers.load_pre.append(_file_closing)


def detach() -> None:
    if _file_closing in bpy.app.handlers.load_pre:
        bpy.app.handlers.load_pre.remove(_file_closing)


def wait(task: Task, timeout: float = 600.0) -> Task:
    """Join the worker and finish on this (main) thread: for scripts and tests without an event loop."""
    if task._thread is not None:
        task._thread.join(timeout)
    if task._thread is not None and task._thread.is_alive():
        raise TimeoutError(f"{task.label} still running after {timeout:g} s")
    if bpy.app.timers.is_registered(task.timer):
        bpy.app.timers.unregister(task.timer)
    task.finish()
    return task


class TaskOperator:
    """The one base of every operator whose work is a :class:`Task` (bakes, previews, thumbnails, jobs):
    modal with Esc to cancel in the UI, blocking in scripts and background mode; reports failures and
    cancellation.  A subclass implements ``_start(context, blocking) -> Task | None`` (None after reporting
    why it could not start)."""

    blocking: BoolProperty(name="Blocking", description="Wait for the work to finish (scripts)", default=False,
                           options={"SKIP_SAVE", "HIDDEN"})

    #: the backend's names of settings -> the panel's (a solid's "exemplar" is the panel's Image)
    setting_names: dict = {}

    def _label(self, setting: str) -> str | None:
        """The panel's name of a backend setting, or None where the panel calls it as the backend does."""
        return self.setting_names.get(setting)

    def _said(self, exc: Exception) -> str:
        """An error in one line, a setting named as the panel names it."""
        label = self._label(exc.setting) if isinstance(exc, backend.SettingError) else None
        return f"{label}: {exc.message}" if label is not None else str(exc)

    def _failure(self, task) -> str:
        return self._said(task.error) if task.error is not None else (task.message or task.status)

    @classmethod
    def poll(cls, context):
        return idle(cls)

    def _start(self, context, blocking: bool):
        """Start the task: a :class:`Task`, or None after reporting why it could not start.  A setting error,
        a missing or altered model or an unreadable file may simply be raised: :meth:`_begin` reports it."""
        raise NotImplementedError

    def _begin(self, context, blocking: bool):
        """:meth:`_start`, with the errors that refuse a start reported in one line (nothing is started)."""
        from importlib import import_module

        refused = (backend.SettingError, OSError, import_module(f"{backend.__name__}.onnx_models").ModelError)
        try:
            return self._start(context, blocking)
        except refused as exc:
            self.report({"ERROR"}, self._said(exc))
            return None

    def execute(self, context):
        task = self._begin(context, blocking=True)
        if task is None:
            return {"CANCELLED"}
        if task.status != "done":
            self.report({"ERROR"} if task.status == "failed" else {"WARNING"}, self._failure(task))
            return {"CANCELLED"}
        return {"FINISHED"}

    def invoke(self, context, event):
        if self.blocking or bpy.app.background:
            return self.execute(context)
        self._task = self._begin(context, blocking=False)
        if self._task is None:
            return {"CANCELLED"}
        context.window_manager.modal_handler_add(self)
        return {"RUNNING_MODAL"}

    def modal(self, context, event):
        task = self._task
        if not task.running:
            if task.status == "failed":
                self.report({"ERROR"}, self._failure(task))
            elif task.status == "cancelled":
                self.report({"WARNING"}, f"{task.label}: cancelled")
            return {"FINISHED"} if task.status == "done" else {"CANCELLED"}
        if event.type == "ESC" and event.value == "PRESS":
            task.cancel()
            return {"RUNNING_MODAL"}
        return {"PASS_THROUGH"}
