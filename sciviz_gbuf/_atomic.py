"""Outputs that are complete or absent.

Every file the package writes under a name the user chose goes through :func:`atomic_output`:
the writer fills a temporary file in the target folder (``.<final name>.<random>.part``, on the
same file system, so the rename is atomic), the temporary is checked (the bytes on disk are the
bytes written, the library's error state is clean), flushed to disk (``fsync``), and only then
renamed over the final name (``os.replace``). On any failure (a full disk, ``EFBIG`` past a file
size limit, a library that reports its errors only to a log) or interruption (SIGTERM, SIGINT),
the temporary is removed and nothing new appears under the final name: an old file of that
name, if any, is left as it was.

Native libraries (GDAL, libtiff, VTK) print their errors straight to file descriptor 2.
:meth:`Part.native` captures that descriptor around a native call, so that the text becomes
part of the one-line :class:`~sciviz_gbuf.errors.OutputError` when the write fails, and is
passed on to ``sys.stderr`` unchanged when it succeeds.

The command line turns SIGTERM and SIGINT into :class:`Interrupted` with
:func:`raising_signals`, so the same clean-up runs on a signal.

The process's other plumbing lives here too: :func:`lazy_exports`, which lets a package's
``__init__`` import its names on first use (so a command starts without the libraries it
does not need).
"""

from __future__ import annotations

import importlib
import os
import re
import secrets
import signal
import sys
import tempfile
import threading
import types
from collections.abc import Iterator, Sequence
from contextlib import contextmanager
from pathlib import Path
from types import FrameType
from typing import NoReturn

from .errors import OutputError, SciVizGBufError

__all__ = [
    "Interrupted",
    "Part",
    "atomic_folder",
    "atomic_output",
    "lazy_exports",
    "native_stderr",
    "one_line",
    "output_group",
    "raising_signals",
    "scratch_file",
]

#: Longest reason quoted in an OutputError (native libraries can print pages).
_REASON_CHARS = 240
_ANSI = re.compile(r"\x1b\[[0-9;]*[A-Za-z]")
_TEMPORARY = re.compile(r"[^\s'\"]*\.[0-9a-f]{8}(?:\.\w+)?\.part\b")
#: Active :func:`output_group` lists, innermost last (outputs are written by the main thread).
_GROUPS: list[list[tuple[Part, bool]]] = []
#: Serialises the redirection of file descriptor 2, which is one per process.
_FD2_LOCK = threading.RLock()
#: Depth of :func:`_signals_deferred` blocks and the signals that arrived inside them.
_DEFER = {"depth": 0, "pending": []}


class Interrupted(BaseException):
    """A signal (SIGTERM, SIGINT) turned into an exception by :func:`raising_signals`.

    A ``BaseException``, like ``KeyboardInterrupt``, so that the ``except Exception`` of
    library code cannot swallow it. :func:`atomic_output` adds the name of every output it
    removed on its way up to :attr:`outputs`.
    """

    def __init__(self, signum: int) -> None:
        super().__init__(signum)
        self.signum = signum
        self.outputs: list[str] = []

    def __str__(self) -> str:
        try:
            name = signal.Signals(self.signum).name
        except ValueError:
            name = f"signal {self.signum}"
        if not self.outputs:
            return f"interrupted by {name}"
        return f"interrupted by {name}: {', '.join(self.outputs)} not written"


def _raise_interrupted(signum: int, frame: FrameType | None) -> None:
    if _DEFER["depth"]:
        # Inside the redirection or restoration of descriptor 2 (see _signals_deferred):
        # raised again once that is whole.
        _DEFER["pending"].append(signum)
        return
    # A second signal of the same kind ends the process the default way, so that a clean-up
    # that hangs can still be stopped.
    signal.signal(signum, signal.SIG_DFL)
    raise Interrupted(signum)


@contextmanager
def _signals_deferred() -> Iterator[None]:
    """Within the block, a signal of :func:`raising_signals` is held and raised as the block
    ends. For the few steps that swap descriptor 2 and ``sys.stderr``: an exception between
    two of them would leave descriptor 2 in the capture file, and the error line of the
    interruption would be written there, not to the terminal. Handlers run in the main thread
    only: a signal held for another thread's block is sent again (``raise_signal``) when it
    ends, and the handler then raises it in the main thread."""
    with _FD2_LOCK:
        _DEFER["depth"] += 1
        try:
            yield
        finally:
            _DEFER["depth"] -= 1
            pending = [] if _DEFER["depth"] else _DEFER["pending"][:]
            if pending:
                _DEFER["pending"].clear()
    for signum in dict.fromkeys(pending):
        signal.raise_signal(signum)


@contextmanager
def raising_signals(
    signums: Sequence[int] = (signal.SIGTERM, signal.SIGINT),
) -> Iterator[None]:
    """Within the block, the signals ``signums`` raise :class:`Interrupted` in the main thread
    (Python runs signal handlers there, between bytecodes, so a long native call finishes
    first). A signal the caller ignores (``SIG_IGN``: ``nohup``, a background job) stays
    ignored; the previous handlers come back afterwards. Outside the main thread, where
    handlers cannot be installed, nothing changes.
    """
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    previous = {}
    for signum in signums:
        current = signal.getsignal(signum)
        if current == signal.SIG_IGN:
            continue
        previous[signum] = signal.SIG_DFL if current is None else current
        signal.signal(signum, _raise_interrupted)
    try:
        yield
    finally:
        for signum, handler in previous.items():
            signal.signal(signum, handler)


def one_line(text: str, limit: int = _REASON_CHARS) -> str:
    """``text`` on one line (runs of white space, newlines included, become one space; ANSI
    colour codes of a log are dropped), shortened to ``limit`` characters."""
    flat = " ".join(_ANSI.sub("", text).split())
    return flat if len(flat) <= limit else flat[: limit - 3].rstrip() + "..."


def _describe(exc: BaseException) -> str:
    """The reason an exception gives: an OSError's ``strerror`` (``No space left on device``),
    else its text, followed by the text of its explicit cause (``raise ... from``)."""
    parts = []
    for e in (exc, exc.__cause__):
        if e is None:
            continue
        text = e.strerror if isinstance(e, OSError) and e.strerror else str(e)
        # rasterio's "Write failed. See previous exception for details.": the cause follows.
        text = text.replace("See previous exception for details.", "").strip()
        if text and text not in parts:
            parts.append(text)
    return "; ".join(parts) or type(exc).__name__


@contextmanager
def _fd2_captured(box: list[str]) -> Iterator[None]:
    """Redirect file descriptor 2 into an anonymous in-memory file for the block; its text is
    appended to ``box`` afterwards. Without a descriptor 2 to save, or a place to put the text
    (no memfd, a full temporary folder), nothing is captured."""
    with _FD2_LOCK:
        try:
            sink = os.memfd_create("sciviz-gbuf-stderr") if hasattr(os, "memfd_create") else None
        except OSError:
            sink = None
        tmp = None
        if sink is None:
            try:
                tmp = tempfile.TemporaryFile()
                sink = tmp.fileno()
            except OSError:
                sink = None
        try:
            saved = os.dup(2) if sink is not None else None
        except OSError:
            saved = None
        if saved is None:
            if tmp is not None:
                tmp.close()
            yield
            return
        python_stderr = None
        redirected = False
        try:
            with _signals_deferred():
                _flush_stderr()
                os.dup2(sink, 2)
                redirected = True
                python_stderr = _bypass(saved)
            yield
        finally:
            # All of the restoration, or none of it, before a signal is raised.
            with _signals_deferred():
                _flush_stderr()
                if python_stderr is not None:
                    sys.stderr, bypass = python_stderr, sys.stderr
                    bypass.close()
                if redirected:
                    os.dup2(saved, 2)
                os.close(saved)
                size = os.lseek(sink, 0, os.SEEK_END)
                os.lseek(sink, 0, os.SEEK_SET)
                data = os.read(sink, size) if size else b""
                if tmp is not None:
                    tmp.close()
                else:
                    os.close(sink)
                if data.strip():
                    box.append(data.decode("utf-8", errors="replace"))


@contextmanager
def native_stderr() -> Iterator[list[str]]:
    """Capture what native libraries (VTK, GDAL) print to file descriptor 2 inside the block,
    for readers to fold into their one-line errors: the yielded list holds the text once the
    block has ended. Python's own ``sys.stderr`` is not captured."""
    box: list[str] = []
    with _fd2_captured(box):
        yield box


def _bypass(saved: int):
    """While descriptor 2 is captured, Python's own ``sys.stderr`` (warnings, logging) keeps
    going where it went, through a duplicate of the saved descriptor: only native output is
    captured. Returns the original ``sys.stderr`` to restore, or None if it is not the
    process's descriptor 2 (a test's capture, a notebook), which is then left alone."""
    stream = sys.stderr
    try:
        if stream is None or stream.fileno() != 2:
            return None
        sys.stderr = open(  # closed when the capture ends
            os.dup(saved),
            "w",
            buffering=1,
            encoding=stream.encoding,
            errors="backslashreplace",
        )
    except (AttributeError, OSError, ValueError):  # no fileno (io.StringIO), closed
        return None
    return stream


def _flush_stderr() -> None:
    try:
        sys.stderr.flush()
    except (AttributeError, OSError, ValueError):  # no stderr, or a closed one
        pass


def _remove(path: Path) -> None:
    """Remove ``path`` and what native writers leave beside it (``<name>.ovr.tmp``,
    ``<name>.aux.xml``): every name starting with it, which its random part makes its own."""
    for p in [path, *path.parent.glob(f"{path.name}.*")]:
        try:
            p.unlink()
        except FileNotFoundError:
            pass
        except OSError:  # best effort: the error being reported is the write's
            pass


def _fsync(path: Path, *, directory: bool = False) -> None:
    fd = os.open(path, os.O_RDONLY | (getattr(os, "O_DIRECTORY", 0) if directory else 0))
    try:
        os.fsync(fd)
    except OSError:
        if not directory:
            raise
        # Some file systems cannot sync a folder (EINVAL): the rename is done all the same.
    finally:
        os.close(fd)


class Part:
    """An output being written: :attr:`path` is the temporary file beside :attr:`final`.

    Attributes
    ----------
    path : pathlib.Path
        The temporary file the writer fills: ``.<final name>.<random>.part``.
    final : pathlib.Path
        The output's name.
    shown : str
        The output's name as the caller gave it (for messages).
    expected_size : int or None
        If set by the writer: the number of bytes written, checked against the file's size
        before the rename.
    """

    def __init__(self, path: str | os.PathLike) -> None:
        self.shown = os.fsdecode(os.fspath(path))
        self.final = Path(path)
        self.path = self.final.with_name(f".{self.final.name}.{secrets.token_hex(4)}.part")
        self.expected_size: int | None = None
        self.committed = False
        self._native: list[tuple[str, bool]] = []  # (text, folded into a failure message)

    def message(self, reason: str) -> str:
        """The one-line message of a failed write of this output, for ``reason``."""
        lines = [
            _ANSI.sub("", ln).strip()
            for text, fold in self._native
            if fold
            for ln in text.splitlines()
        ]
        said = one_line(" ".join(dict.fromkeys(ln for ln in lines if ln)))  # each line once
        # A temporary's name in a library's text means the output: say the output's name.
        why = _TEMPORARY.sub(self.final.name, one_line(reason))
        said = _TEMPORARY.sub(self.final.name, said)
        if said and said not in why:
            why = f"{why}; {said}" if why else said
        return f"{self.shown}: write failed ({one_line(why)}); the file was not written"

    def fail(self, reason: str | BaseException) -> NoReturn:
        """Raise the :class:`~sciviz_gbuf.errors.OutputError` of a failed write, for a reason
        or a library's exception (the temporary is removed by :func:`atomic_output` on the
        way up)."""
        why = _describe(reason) if isinstance(reason, BaseException) else reason
        raise OutputError(self.message(why))

    @contextmanager
    def native(self, *, fold: bool = True) -> Iterator[None]:
        """Capture what native code prints to file descriptor 2 during the block: it is
        folded into the message if the write fails (``fold=False``: dropped, when the writer
        knows the reason better), and passed on to ``sys.stderr`` after a successful one.
        Python's own ``sys.stderr`` is not captured. Thread-safe; the redirection is
        process-wide, so keep the block to the native call."""
        box: list[str] = []
        try:
            with _fd2_captured(box):
                yield
        finally:
            self._native.extend((text, fold) for text in box)

    def _check(self, fsync: bool) -> None:
        """The temporary is whole (and on disk): ready to be renamed."""
        if not self.path.is_file():
            self.fail("the writer produced no file")
        size = self.path.stat().st_size
        if self.expected_size is not None and size != self.expected_size:
            self.fail(f"{size} bytes on disk of {self.expected_size} written")
        if fsync:
            _fsync(self.path)

    def _rename(self, fsync: bool) -> None:
        os.replace(self.path, self.final)
        self.committed = True
        _remove(self.path)  # what a native writer left beside it
        if fsync:
            _fsync(self.final.parent, directory=True)

    def _replay(self) -> None:
        for text, _ in self._native:
            try:
                sys.stderr.write(text)
            except (AttributeError, OSError, ValueError):
                pass
        self._native.clear()


@contextmanager
def atomic_output(path: str | os.PathLike, *, fsync: bool = True) -> Iterator[Part]:
    """Write ``path`` completely or not at all.

    The block writes the temporary file ``part.path`` (in the same folder); when it ends
    without an exception, the file is checked (it exists; its size is ``part.expected_size``
    if the writer set it), synced to disk and renamed to ``path``. On any exception, including
    :class:`Interrupted` and ``KeyboardInterrupt``, the temporary is removed. OS errors (disk
    full, file too large, permission) become an :class:`~sciviz_gbuf.errors.OutputError`
    naming ``path``; errors of this package pass unchanged; other exceptions are re-raised.

    Parameters
    ----------
    path : str or path-like
        The output file; its folder must exist.
    fsync : bool, optional
        Sync the file and its folder to disk (default True), so that a crash after the rename
        cannot leave an empty or partial file under the final name.

    Yields
    ------
    Part
        Its ``path`` is the temporary to write; ``fail(reason)`` raises the OutputError;
        ``native()`` captures a native library's messages.
    """
    part = Part(path)
    try:
        yield part
        part._check(fsync)
        if _GROUPS:
            _GROUPS[-1].append((part, fsync))  # renamed when the group ends
        else:
            part._rename(fsync)
    except Interrupted as exc:
        _remove(part.path)
        if not part.committed:
            exc.outputs.append(part.shown)
        raise
    except SciVizGBufError:
        _remove(part.path)
        raise
    except OSError as exc:
        _remove(part.path)
        raise OutputError(part.message(_describe(exc))) from exc
    except BaseException:
        _remove(part.path)
        raise
    part._replay()


@contextmanager
def output_group() -> Iterator[None]:
    """All outputs of the block, or none: each :func:`atomic_output` within it is checked as
    usual but renamed to its name only when the block ends without an exception; on an
    exception every one of them is removed (a command that exits with an error leaves none
    of its outputs, not the first of two). Groups nest; the innermost one collects."""
    group: list[tuple[Part, bool]] = []
    _GROUPS.append(group)
    try:
        yield
    except BaseException as exc:
        _GROUPS.remove(group)
        for part, _ in group:
            _remove(part.path)
            if isinstance(exc, Interrupted) and part.shown not in exc.outputs:
                exc.outputs.append(part.shown)
        raise
    _GROUPS.remove(group)
    try:
        for part, fsync in group:
            part._rename(fsync)
    except BaseException as exc:
        for part, _ in group:
            if not part.committed:
                _remove(part.path)
        if isinstance(exc, OSError):
            raise OutputError(part.message(_describe(exc))) from exc
        raise


@contextmanager
def scratch_file(final: str | os.PathLike, tag: str) -> Iterator[Path]:
    """A temporary working file beside the output ``final`` (``.<final name>.<random>.<tag>.part``),
    removed when the block ends, however it ends."""
    f = Path(final)
    path = f.with_name(f".{f.name}.{secrets.token_hex(4)}.{tag}.part")
    try:
        yield path
    finally:
        _remove(path)


@contextmanager
def atomic_folder(path: str | os.PathLike) -> Iterator[Path]:
    """Write the folder ``path`` completely or not at all (a tile pyramid: thousands of files).

    The block fills a temporary folder beside it (``.<name>.<random>.part``), which is renamed
    to ``path`` when the block ends without an exception (``path`` must not exist, or be an
    empty folder, which it replaces); on any exception, interrupts included, the temporary
    folder is removed. OS errors become an :class:`~sciviz_gbuf.errors.OutputError` naming
    ``path``.
    """
    import shutil

    final = Path(path)
    tmp = final.with_name(f".{final.name}.{secrets.token_hex(4)}.part")
    try:
        tmp.mkdir()
        yield tmp
        if final.is_dir():
            final.rmdir()  # empty (else rmdir fails: nothing is replaced)
        os.replace(tmp, final)
    except BaseException as exc:
        shutil.rmtree(tmp, ignore_errors=True)
        if isinstance(exc, OSError):
            raise OutputError(f"{final}: could not be written ({_describe(exc)})") from exc
        raise


# ------------------------------------------------------------------ lazy package exports
class _LazyPackage(types.ModuleType):
    """A package whose names are imported on first use (:func:`lazy_exports`). A submodule
    that has the name of a function it defines (``core.capture``) would replace that function
    as the package's attribute when it is imported: the package keeps the function."""

    _keep: frozenset[str] = frozenset()

    def __setattr__(self, name: str, value: object) -> None:
        if name in self._keep and isinstance(value, types.ModuleType):
            return
        super().__setattr__(name, value)


def lazy_exports(package: str, exports: dict[str, str], submodules: tuple[str, ...] = ()) -> None:
    """Make ``exports`` (public name -> module that defines it, relative to ``package``:
    ``"camera"``, or ``"..core.framing"`` for a re-export from another package) and
    ``submodules`` attributes of the package ``package`` that are imported on first use (PEP
    562): importing a package then costs nothing, and a command that needs only the DEM
    reader and the map does not wait for VTK and PyVista. Called at the end of a package's
    ``__init__`` (internal to sciviz_gbuf; not part of the public API)."""
    module = sys.modules[package]

    def __getattr__(name: str) -> object:
        target = exports.get(name)
        if target is not None:
            relative = target if target.startswith(".") else f".{target}"
            value = getattr(importlib.import_module(relative, package), name)
        elif name in submodules:
            value = importlib.import_module(f".{name}", package)
        else:
            raise AttributeError(f"module {package!r} has no attribute {name!r}")
        vars(module)[name] = value  # later look-ups find it directly
        return value

    def __dir__() -> list[str]:
        return sorted({*vars(module), *exports, *submodules})

    module.__getattr__ = __getattr__  # type: ignore[method-assign]
    module.__dir__ = __dir__  # type: ignore[method-assign]
    keep = frozenset(n for n, m in exports.items() if m.rsplit(".", 1)[-1] == n)
    if keep:
        module.__class__ = _LazyPackage
        module._keep = keep
