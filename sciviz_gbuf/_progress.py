"""A staged progress bar following PyVista's ``progress_bar=`` convention (tqdm)."""

from __future__ import annotations

from collections.abc import Iterator
from contextlib import contextmanager


class _Null:
    def step(self, label: str) -> None:
        pass


class _Bar:
    def __init__(self, bar) -> None:
        self._bar = bar

    def step(self, label: str) -> None:
        """Finish the current stage and name the next one."""
        self._bar.set_postfix_str(label)
        self._bar.update(1)


@contextmanager
def progress(enabled: bool, total: int, desc: str) -> Iterator[_Bar | _Null]:
    """Yield an object whose ``step(label)`` advances a bar of ``total`` stages."""
    if not enabled:
        yield _Null()
        return
    from tqdm import tqdm

    with tqdm(total=total, desc=desc, leave=False) as bar:
        yield _Bar(bar)
