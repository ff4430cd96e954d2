"""An agent's own random streams, apart from the process-global generators.

:class:`PolicyRandom` holds the streams an agent draws its ``deterministic=False`` actions
from; :func:`global_rngs_kept` runs library code that draws from or re-seeds the global
generators (building a network, SB3's ``BaseAlgorithm.load``) and puts their states back.
"""

from __future__ import annotations

from collections.abc import Iterator, Sequence
from contextlib import contextmanager

import numpy as np

from policies.base import SEEDS_ALLOWED, check_seed, row_seeds

__all__ = ["PolicyRandom", "global_rngs_kept"]


@contextmanager
def global_rngs_kept() -> Iterator[None]:
    """Run a block of library code that draws from or re-seeds the process-global generators
    and put the states of ``random``, ``numpy.random`` and torch's CPU generator back after:
    building a network draws its initial weights (overwritten by the file's) from torch's,
    and SB3's ``BaseAlgorithm.load`` re-seeds all three with the seed saved in the zip."""
    import random

    import torch

    py_state = random.getstate()
    np_state = np.random.get_state()  # noqa: NPY002 (saved to be put back, never drawn from)
    try:
        with torch.random.fork_rng(devices=[]):
            yield
    finally:
        random.setstate(py_state)
        np.random.set_state(np_state)  # noqa: NPY002 (the caller's state, put back)


class PolicyRandom:
    """An agent's own random streams for ``deterministic=False`` actions: the project's one
    random path, so the process-global ``torch``, ``numpy`` and ``random`` generators are
    neither drawn from nor re-seeded (SB3's ``set_random_seed`` would re-seed all three).

    - ``torch``: the state of a CPU ``torch.Generator`` seeded with ``seed`` (the state
      ``torch.manual_seed(seed)`` would give). SB3's ``predict`` samples from the global CPU
      generator, so :meth:`torch_stream` runs a block with the global state swapped for this
      one (``torch.random.fork_rng``: the caller's state is put back after, this one saved).
      The agents act on the CPU (``device="cpu"``), so no CUDA state is involved.
    - ``numpy``: a ``numpy.random.Generator`` seeded with ``seed``, for draws the agent makes
      itself (a DQN's epsilon-greedy exploration, :class:`policies.agents.sb3_agents.SB3Agent`).

    ``seed=None`` (also a new object given no seed) seeds both from fresh operating-system
    entropy: not reproducible, and still no global generator touched.

    >>> import torch
    >>> rng, before = PolicyRandom(seed=3), torch.get_rng_state()
    >>> with rng.torch_stream():
    ...     a = torch.rand(2)
    >>> bool((torch.get_rng_state() == before).all())  # the global generator: untouched
    True
    >>> bool((a == torch.rand(2, generator=torch.Generator().manual_seed(3))).all())
    True
    """

    def __init__(self, seed: int | Sequence[int] | None = None) -> None:
        self.seed(seed)

    def seed(self, seed: int | Sequence[int] | None) -> None:
        """Re-seed both streams. A sequence of seeds (a batch of episodes) uses its first
        seed: one stream serves the whole batch (module docstring of the agents). A seed is
        an integer >= 0 (``int``, a numpy integer, an integer array), taken modulo ``2**32``
        as SB3's ``set_random_seed`` did (numpy's range; the benchmark's policy seeds are
        64-bit); anything else (a float, a bool, a string, a negative or an empty batch)
        raises ``ValueError`` naming it, before the streams change."""
        import torch

        first = _first_seed(seed)
        if first is None:
            entropy = np.random.SeedSequence()
            self.numpy = np.random.default_rng(entropy)
            torch_seed = int(entropy.generate_state(1, np.uint64)[0])
        else:
            torch_seed = first % 2**32  # as SB3's set_random_seed did (numpy's range)
            self.numpy = np.random.default_rng(torch_seed)
        self._torch_state = torch.Generator().manual_seed(torch_seed).get_state()

    @contextmanager
    def torch_stream(self) -> Iterator[None]:
        """Within the block torch's global CPU generator draws from this stream; after it,
        the global generator is back where it was and this stream continues from where the
        block left it (also when the block raises)."""
        import torch

        with torch.random.fork_rng(devices=[]):
            torch.set_rng_state(self._torch_state)
            try:
                yield
            finally:
                self._torch_state = torch.get_rng_state()


def _first_seed(seed: object) -> int | None:
    """The seed :meth:`PolicyRandom.seed` uses: None, an integer >= 0, or the first of a
    non-empty batch of them (every one checked: :func:`policies.base.row_seeds`);
    ``ValueError`` naming anything else."""
    if seed is None:
        return None
    rows = row_seeds(seed)
    if rows is None:
        return check_seed(seed)
    if not rows:
        raise ValueError(f"seed = {seed!r} must be {SEEDS_ALLOWED}")
    return rows[0]
