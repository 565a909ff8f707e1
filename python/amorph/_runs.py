"""Whole runs of Amorph's search from Python, and run stores read back as tables."""

from __future__ import annotations

import os
from typing import Any, Callable, Dict, Iterator, List, Optional, Sequence, Union

import numpy as np

from . import _amorph
from ._amorph import Genome, Outcome, Scene

PathLike = Union[str, "os.PathLike[str]"]

# Seconds between looks at the run's events: also how soon Ctrl-C is heard.
_POLL = 0.25


class Run:
    """A run of Amorph's search in this process, started at once.

    Iterate over it for its epochs (a dict each: ``epoch``, ``evaluations``, ``wall_seconds``,
    ``resolution``, ``best_fitness``, ``best_figure`` and ``islands``, one row per island as in
    ``history.csv``). Once the iteration ends, :attr:`summary` holds the run's summary. Ctrl-C
    (KeyboardInterrupt) stops the run, keeping every finished evaluation in its store; the same
    config with ``resume=True`` then continues it to the same bits as an uninterrupted run.

    ``config`` is a config file (None: the quickstart). ``overrides`` set its keys as
    ``coordinator --set`` does, a dict for a table: ``Run("configs/circular_arc.toml",
    seed=3, budget={"evaluations": 2000})``.
    """

    def __init__(
        self,
        config: Optional[PathLike] = None,
        *,
        resume: bool = False,
        fresh: bool = False,
        local_workers: Optional[int] = None,
        listen: Optional[str] = None,
        **overrides: Any,
    ) -> None:
        self.summary: Optional[Dict[str, Any]] = None
        self._handle = _amorph.RunHandle(
            None if config is None else os.fspath(config),
            overrides,
            resume=resume,
            fresh=fresh,
            local_workers=local_workers,
            listen=listen,
        )

    @property
    def run_dir(self) -> str:
        """The run's results folder."""
        return os.fspath(self._handle.run_dir)

    def __iter__(self) -> Iterator[Dict[str, Any]]:
        return self

    def __next__(self) -> Dict[str, Any]:
        if self.summary is not None:
            raise StopIteration
        while True:
            try:
                event = self._handle.next_event(_POLL)
            except KeyboardInterrupt:
                self.stop()
                self._settle()
                raise
            if event is None:
                continue
            kind, value = event
            if kind == "epoch":
                return value
            self.summary = value
            raise StopIteration

    def stop(self) -> None:
        """Asks the run to stop; iterating then ends once it has."""
        self._handle.stop()

    def wait(self) -> Dict[str, Any]:
        """Runs to the end and returns the summary."""
        for _ in self:
            pass
        assert self.summary is not None
        return self.summary

    def _settle(self) -> None:
        """Waits for a stopped run to wind down; its outcome is the stop, not an error."""
        while True:
            try:
                event = self._handle.next_event(_POLL)
            except RuntimeError:
                return
            if event is not None and event[0] == "done":
                self.summary = event[1]
                return


def run(
    config: Optional[PathLike] = None,
    *,
    progress: Optional[Callable[[Dict[str, Any]], None]] = None,
    resume: bool = False,
    fresh: bool = False,
    local_workers: Optional[int] = None,
    listen: Optional[str] = None,
    **overrides: Any,
) -> Dict[str, Any]:
    """Runs Amorph's search on ``config`` (None: the quickstart) to its end and returns its summary.

    ``progress`` is called with each epoch's dict (see :class:`Run`). The summary holds ``stop``
    (``evaluation_budget``, ``wall_time``, ``target_reached`` or ``shutdown``), ``epochs``,
    ``evaluations``, ``wall_seconds``, ``resolution``, ``best_genome``, ``best_outcome``,
    ``best_task``, ``run_dir`` and ``report``. Ctrl-C stops the run and raises KeyboardInterrupt;
    ``resume=True`` continues it.
    """
    handle = Run(
        config,
        resume=resume,
        fresh=fresh,
        local_workers=local_workers,
        listen=listen,
        **overrides,
    )
    for epoch in handle:
        if progress is not None:
            progress(epoch)
    assert handle.summary is not None
    return handle.summary


class Table:
    """One table of a run store: columns by name, numpy arrays for numbers (NaN or -1 where the
    store holds NULL) and lists for text."""

    def __init__(self, columns: Dict[str, Any]) -> None:
        self._columns = columns

    @property
    def columns(self) -> List[str]:
        return list(self._columns)

    def __getitem__(self, name: str) -> Any:
        return self._columns[name]

    def __len__(self) -> int:
        first = next(iter(self._columns.values()), [])
        return len(first)

    def rows(self) -> List[Dict[str, Any]]:
        """The table as a list of dicts, one per row."""
        names = self.columns
        values = [
            c.tolist() if isinstance(c, np.ndarray) else c for c in self._columns.values()
        ]
        return [dict(zip(names, row)) for row in zip(*values)]

    def to_pandas(self) -> Any:
        """The table as a pandas DataFrame (pandas is not a dependency: install it to use this)."""
        try:
            import pandas
        except ImportError as e:  # pragma: no cover - depends on the environment
            raise ImportError("Table.to_pandas needs pandas: pip install pandas") from e
        return pandas.DataFrame(self._columns)

    def __repr__(self) -> str:
        return f"Table({len(self)} rows: {', '.join(self.columns)})"


class RunStore:
    """A run's store as it was when read (:func:`open_run`): its config and its tables.

    :attr:`evaluations` has one row per evaluation (``task_id``, ``epoch``, ``island``,
    ``purpose``, ``resolution``, ``fitness``, ``worker``, ``wall_seconds``, ``finished_unix``,
    and ``genome`` and ``outcome`` as JSON); :attr:`epochs` (also :attr:`history`) one per epoch;
    :attr:`populations` who held each slot after each epoch; :attr:`migrations` each migrant.
    """

    def __init__(self, data: Dict[str, Any]) -> None:
        self.path: str = os.fspath(data["path"])
        self.config: str = data["config"]
        self.evaluations = Table(data["evaluations"])
        self.epochs = Table(data["epochs"])
        self.populations = Table(data["populations"])
        self.migrations = Table(data["migrations"])
        self._rows = {int(t): i for i, t in enumerate(self.evaluations["task_id"])}
        self._scene: Optional[Scene] = None

    @property
    def history(self) -> Table:
        """The run's progress, one row per epoch: the :attr:`epochs` table."""
        return self.epochs

    @property
    def scene(self) -> Scene:
        """The run's scene, from its stored config."""
        if self._scene is None:
            base = os.path.dirname(os.path.dirname(self.path))
            self._scene = Scene.from_toml(self.config, base_dir=base)
        return self._scene

    def genome(self, task_id: int) -> Genome:
        """The genome evaluated as task ``task_id``."""
        return Genome.from_json(self.evaluations["genome"][self._row(task_id)])

    def outcome(self, task_id: int) -> Outcome:
        """The outcome that holds for task ``task_id``."""
        return Outcome.from_json(self.evaluations["outcome"][self._row(task_id)], self.scene)

    def population(self, epoch: Optional[int] = None) -> List[List[int]]:
        """Each island's task ids after ``epoch`` (default: the last recorded), in slot order."""
        epochs = self.populations["epoch"]
        if len(epochs) == 0:
            return []
        at = int(epochs.max()) if epoch is None else epoch
        rows = np.flatnonzero(epochs == at)
        islands: Dict[int, List[int]] = {}
        for r in rows:
            islands.setdefault(int(self.populations["island"][r]), []).append(
                int(self.populations["task_id"][r])
            )
        return [islands[i] for i in sorted(islands)]

    @property
    def best(self) -> Optional[int]:
        """The task id of the best design so far: the fittest of the last recorded populations
        (for a :class:`Cluster`'s store, which has none, the fittest evaluation), or None."""
        fitness = self.evaluations["fitness"]
        members: Sequence[int] = [t for island in self.population() for t in island]
        if not members:
            members = [int(t) for t in self.evaluations["task_id"]]
        scored = [(fitness[self._row(t)], t) for t in members if not np.isnan(fitness[self._row(t)])]
        if not scored:
            return None
        # The first of equals, as the search's own tie rule keeps the earlier individual.
        best = max(f for f, _ in scored)
        return next(t for f, t in scored if f == best)

    def _row(self, task_id: int) -> int:
        try:
            return self._rows[int(task_id)]
        except KeyError:
            raise KeyError(f"{self.path}: no evaluation with task id {task_id}") from None

    def __repr__(self) -> str:
        return f"RunStore({self.path!r}: {len(self.evaluations)} evaluations, {len(self.epochs)} epochs)"


def open_run(path: PathLike) -> RunStore:
    """Reads a run's store: a results folder (``results/<name>``) or its ``run.sqlite``.

    The store is read at one moment, also while a run writes it (it is in WAL mode): open it
    again to see what came since.
    """
    return RunStore(_amorph.read_run_store(os.fspath(path)))
