"""Fixtures for the studio's tests.

The model tests need no display. The GUI tests need a real X server (pyvistaqt's
``QtInteractor`` needs OpenGL; Qt's ``offscreen`` platform cannot give it one), so
this file starts its own ``Xvfb`` on a free display number the first time a test
asks for the Qt application, and points ``DISPLAY`` at it. ``xvfb-run`` is not
needed. If the ``Xvfb`` program is missing the GUI tests are skipped, saying so.

Xvfb is started with ``-terminate``: it exits by itself when its last client (this
test process) disconnects, so it never outlives the tests, and it is never killed
under a live Qt connection (which would make Qt abort the process). Tests that run
the app in a subprocess also request ``qapp``, so this process is connected first
and a subprocess leaving does not end the server.
"""

from __future__ import annotations

import os
import select
import shutil
import signal
import tempfile
import time

import pytest

SCREEN = "1600x1100x24"


class _Xvfb:
    """Xvfb started with posix_spawn: no Popen object is left to complain that it outlives the tests."""

    def __init__(self):
        self.pid: int | None = None
        self.display: str | None = None
        self.error: str | None = None

    def start(self) -> None:
        exe = shutil.which("Xvfb")
        if exe is None:
            self.error = "Xvfb is not installed (Debian: apt-get install xvfb); the GUI tests need an X server"
            return
        read_fd, write_fd = os.pipe()
        log = tempfile.TemporaryFile()
        try:
            os.set_inheritable(write_fd, True)
            argv = [exe, "-displayfd", str(write_fd), "-screen", "0", SCREEN, "-nolisten", "tcp", "-terminate"]
            self.pid = os.posix_spawn(exe, argv, os.environ, file_actions=[
                (os.POSIX_SPAWN_OPEN, 0, os.devnull, os.O_RDONLY, 0),
                (os.POSIX_SPAWN_DUP2, log.fileno(), 1),
                (os.POSIX_SPAWN_DUP2, log.fileno(), 2),
            ])
        except OSError as exc:
            os.close(read_fd)
            os.close(write_fd)
            log.close()
            self.error = f"Xvfb could not be started: {exc}"
            return
        os.close(write_fd)
        data = b""
        deadline = time.monotonic() + 20.0
        try:
            while not data.endswith(b"\n") and time.monotonic() < deadline:
                ready, _, _ = select.select([read_fd], [], [], 0.2)
                if ready:
                    chunk = os.read(read_fd, 64)
                    if not chunk:
                        break
                    data += chunk
                elif self._exited():
                    break
        finally:
            os.close(read_fd)
        if not data.strip().isdigit():
            log.seek(0)
            err = log.read()[-500:].decode(errors="replace").strip()
            self.stop()
            self.error = f"Xvfb did not start: {err or 'no display number'}"
        else:
            self.display = ":" + data.decode().strip()
        log.close()

    def _exited(self) -> bool:
        if self.pid is None:
            return True
        pid, _status = os.waitpid(self.pid, os.WNOHANG)
        if pid:
            self.pid = None
        return pid != 0

    def stop(self) -> None:
        if self.pid is None or self._exited():
            return
        os.kill(self.pid, signal.SIGTERM)
        deadline = time.monotonic() + 5.0
        while not self._exited() and time.monotonic() < deadline:
            time.sleep(0.05)
        if self.pid is not None:
            os.kill(self.pid, signal.SIGKILL)
            os.waitpid(self.pid, 0)
            self.pid = None


_xvfb = _Xvfb()


@pytest.fixture(scope="session")
def x_display():
    """The display of a private Xvfb server (started once per test session)."""
    if _xvfb.display is None and _xvfb.error is None:
        _xvfb.start()
    if _xvfb.display is None:
        pytest.skip(_xvfb.error or "no X server")
    os.environ["DISPLAY"] = _xvfb.display
    os.environ["QT_QPA_PLATFORM"] = "xcb"
    os.environ.pop("WAYLAND_DISPLAY", None)
    yield _xvfb.display
    from PySide6 import QtWidgets

    if QtWidgets.QApplication.instance() is None:
        _xvfb.stop()  # nobody connected: stop it now; otherwise -terminate ends it when we disconnect


@pytest.fixture(scope="session")
def qapp_args(x_display):
    """pytest-qt makes its QApplication from these: depending on x_display starts Xvfb first."""
    from gsik_studio.qt_compat import protect_none

    protect_none()  # PySide6 6.12 on Python 3.11 drops a reference to None per void call
    return ["gsik-studio-tests"]


@pytest.fixture()
def studio_settings(tmp_path):
    """An isolated QSettings (an INI file in tmp_path), so tests never touch the user's settings."""
    from PySide6 import QtCore

    return QtCore.QSettings(str(tmp_path / "studio.ini"), QtCore.QSettings.IniFormat)


@pytest.fixture()
def window(qtbot, studio_settings):
    """The studio window, shown in the private Xvfb, with isolated settings."""
    from gsik_studio.window import MainWindow

    w = MainWindow(settings=studio_settings)
    w.resize(1280, 860)
    w.show()
    qtbot.waitExposed(w)
    w.activateWindow()
    qtbot.wait(50)
    yield w
    w.doc.history.set_clean()  # no "unsaved changes" question on teardown
    w.close()


@pytest.fixture()
def boxes(monkeypatch):
    """Records QMessageBox calls instead of showing them; ``answer`` is returned from question()."""
    from PySide6.QtWidgets import QMessageBox

    calls = {"critical": [], "warning": [], "question": [], "answer": QMessageBox.Discard}

    def record(kind):
        def f(_parent, title, text, *args, **kwargs):
            calls[kind].append((title, text))
            return calls["answer"] if kind == "question" else QMessageBox.Ok
        return f

    for kind in ("critical", "warning", "question"):
        monkeypatch.setattr(QMessageBox, kind, staticmethod(record(kind)))
    return calls
