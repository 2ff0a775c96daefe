"""One random-number stream shared by worker threads, in the order a single thread would draw.

The NumPy engine traces a batch of paths either in one thread or split into contiguous parts
traced by one thread each (their NumPy work and Embree queries then run on all cores). The
numbers must not depend on that choice: every draw of the serial tracer,
``rng.random(k)`` over the ``k`` live paths, is the concatenation of the parts' draws in part
order (boolean masks keep the paths' order, so part 0's live paths come first). A draw of
``k`` doubles from NumPy's ``Generator.random`` is the next ``k`` doubles of the stream whatever
the call sizes, so the parts get exactly the serial numbers if their draws are served in the
serial program order and, within one draw, in part order.

Each draw is labelled with a *tag*: a tuple of ints increasing in the serial program order
(bounce, site, shadow layer, call counter; see ``_Tracer.paths``). :class:`LockstepRandom`
serves the smallest pending tag once every part still running has posted a request (a part
that is already past a tag, or has finished, draws nothing there — exactly what the serial
tracer does with its paths that left the batch).
"""

from __future__ import annotations

import threading
from typing import Protocol

import numpy as np


class Draws(Protocol):
    """A source of uniform [0, 1) doubles with program-order tags (see the module docstring)."""

    def at(self, *tag: int) -> None:
        """Label the following draws (a new site of the program)."""
        ...

    def random(self, size: int) -> np.ndarray:
        """``size`` uniform doubles in [0, 1)."""
        ...


class SerialDraws:
    """The plain stream of one thread: tags are ignored."""

    def __init__(self, rng: np.random.Generator):
        self.rng = rng

    def at(self, *tag: int) -> None:
        pass

    def random(self, size: int) -> np.ndarray:
        return self.rng.random(size)


class LockstepRandom:
    """Serve ``parts`` threads' tagged draws from one generator in serial order."""

    def __init__(self, rng: np.random.Generator, parts: int):
        self.rng = rng
        self.active = set(range(parts))
        self.pending: dict[int, tuple[tuple[int, ...], int]] = {}
        self.results: dict[int, np.ndarray] = {}
        self.cv = threading.Condition()

    def part(self, index: int) -> PartDraws:
        return PartDraws(self, index)

    def _serve(self) -> None:
        # called with the lock held: serve the smallest tag while every running part waits
        while self.active and all(p in self.pending for p in self.active):
            tag = min(t for t, _ in self.pending.values())
            parts = sorted(p for p, (t, _) in self.pending.items() if t == tag)
            sizes = [self.pending[p][1] for p in parts]
            numbers = self.rng.random(sum(sizes))
            start = 0
            for p, k in zip(parts, sizes):
                self.results[p] = numbers[start:start + k]
                start += k
                del self.pending[p]
            self.cv.notify_all()

    def draw(self, index: int, tag: tuple[int, ...], size: int) -> np.ndarray:
        with self.cv:
            self.pending[index] = (tag, int(size))
            self._serve()
            while index not in self.results:
                self.cv.wait()
            return self.results.pop(index)

    def finish(self, index: int) -> None:
        """Part ``index`` draws no more (it returned or failed)."""
        with self.cv:
            self.active.discard(index)
            self.pending.pop(index, None)
            self._serve()
            self.cv.notify_all()


class PartDraws:
    """One part's view of a :class:`LockstepRandom` (a :class:`Draws`)."""

    def __init__(self, owner: LockstepRandom, index: int):
        self.owner = owner
        self.index = index
        self.tag: tuple[int, ...] = ()
        self.count = 0

    def at(self, *tag: int) -> None:
        self.tag = tag
        self.count = 0

    def random(self, size: int) -> np.ndarray:
        self.count += 1
        return self.owner.draw(self.index, self.tag + (self.count,), size)
