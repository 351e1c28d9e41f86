"""The run loop's operations: everything done between kernel calls, each with a trigger.

The model is HOOMD-blue's ``Simulation.operations`` with its ``Trigger`` classes: the loop
asks every operation for the step at which it is next due, ends the kernel call there,
and runs, in one documented order, each operation that is due. A new kind of event is a
new :class:`Operation` (a class, or a :class:`Callback` with a trigger), never a new
counter in :class:`dpm.Simulation`.

Order when several are due at one step (``Operation.order``):

1. :class:`CellSort` (10): the backend's cell-order renumbering check;
2. :class:`FlowEvents` (20): outlets remove, then inlets insert;
3. :class:`Frames` (30): an output frame (then the ``dpm_on_output`` hook);
4. :class:`BoundarySwitches` (40): boundaries switched off or on at their times;
5. periodic checkpoints (50, :class:`dpm.checkpoint.Schedule`);
6. the script's own operations (100 unless they say otherwise), in the order added.

Each runs with the host state current (an MPI backend gathers it, a device backend
downloads it) unless it says it needs none (``needs_host = False``).

A script adds its own: ``sim.operations.add(dpm.Callback(report, every_steps=1000))``
calls ``report(sim)`` every 1,000 steps (counted from step 0), between kernel calls,
after the built-in operations due at that step; ``sim.operations.remove(op)`` takes it
away. A callback is part of the scene a checkpoint stores: its function is stored by
name (a function of the script, at module level).
"""

from __future__ import annotations

from collections.abc import Callable, Iterator
from typing import TYPE_CHECKING, Any, ClassVar

from .errors import ParameterError

if TYPE_CHECKING:
    from .simulation import Simulation


# ----------------------------------------------------------------- triggers
class Trigger:
    """When an operation runs: :meth:`next` gives the first step after ``step`` at which
    it fires."""

    def next(self, step: int) -> int:
        raise NotImplementedError

    def __call__(self, step: int) -> bool:
        """Whether it fires at ``step``."""
        return self.next(step - 1) == step


class Periodic(Trigger):
    """Every ``period`` steps, at the steps ``phase + k * period``."""

    def __init__(self, period: int, phase: int = 0) -> None:
        if isinstance(period, bool) or not isinstance(period, int) or period < 1:
            raise ParameterError(f"Periodic(): period={period!r}; allowed: an integer >= 1 "
                                 "(steps)")
        if isinstance(phase, bool) or not isinstance(phase, int):
            raise ParameterError(f"Periodic(): phase={phase!r}; allowed: an integer (a step)")
        self.period = int(period)
        self.phase = int(phase)

    def next(self, step: int) -> int:
        return self.phase + ((step - self.phase) // self.period + 1) * self.period

    def __repr__(self) -> str:
        return f"Periodic(period={self.period}, phase={self.phase})"


# ----------------------------------------------------------------- operations
class Operation:
    """Something the run loop does between kernel calls when it is due.

    Subclasses give :meth:`next_step` (the step at which it is next due, None when not
    scheduled) and :meth:`run`; :meth:`start` is called when a run starts (before its
    first kernel call) and :meth:`dt_changed` when ``sim.dt`` changes."""

    #: where it runs among the operations due at one step (lower first)
    order: ClassVar[int] = 100
    #: whether the host state must be current before it runs
    needs_host: bool = True

    def next_step(self, sim: Simulation) -> int | None:
        return None

    def run(self, sim: Simulation) -> None:
        raise NotImplementedError

    def start(self, sim: Simulation) -> None:
        """A run starts (the scene is prepared, its first kernel call is next)."""

    def dt_changed(self, sim: Simulation) -> None:
        """``sim.dt`` changed between runs."""


class CellSort(Operation):
    """The backend's renumbering of the bodies in cell order (``backend.sorts()``): checked
    every ``SORT_CHECK_STEPS`` steps counted from step 0 (the same steps however the run
    is split), where ``backend.sort_due()`` decides."""

    order = 10

    def __init__(self) -> None:
        self.next: int | None = None

    def next_step(self, sim: Simulation) -> int | None:
        return self.next

    def schedule(self, sim: Simulation) -> None:
        self.next = None
        if sim.backend.sorts():
            from .backends.cpu import SORT_CHECK_STEPS

            self.next = (sim.step_count // SORT_CHECK_STEPS + 1) * SORT_CHECK_STEPS

    def start(self, sim: Simulation) -> None:
        self.schedule(sim)

    def run(self, sim: Simulation) -> None:
        sim.backend.sort_due()
        self.schedule(sim)


class FlowEvents(Operation):
    """The flow event of the inlets and outlets (outlets remove, then inlets insert):
    every ``min(every)`` of them in steps, counted from the last change of dt."""

    order = 20

    def __init__(self) -> None:
        self.every = 0  # (steps; 0: no inlet or outlet)
        self.next = 0

    def next_step(self, sim: Simulation) -> int | None:
        return self.next if self.every else None

    def schedule(self, sim: Simulation) -> None:
        flows = sim.inlets + sim.outlets
        fe = max(1, round(min(f.every for f in flows) / sim.dt)) if flows else 0
        if fe != self.every:
            self.every = fe
            if fe:
                s0 = sim._step0
                self.next = s0 + ((sim.step_count - s0) // fe + 1) * fe

    def start(self, sim: Simulation) -> None:
        self.schedule(sim)

    def run(self, sim: Simulation) -> None:
        from . import population

        self.next += self.every
        population.flow_event(sim)
        sim.operations.sort.schedule(sim)  # (an inlet may grow the scene past SORT_FROM)


class Frames(Operation):
    """Output frames (:meth:`dpm.Simulation.output`): every ``every`` seconds (kept in
    seconds when dt changes) or ``every_steps`` steps, while a file is being written."""

    order = 30
    needs_host = False  # (writing a frame brings the host state up itself)

    def __init__(self) -> None:
        self.every: int | None = None  # steps
        self.every_s: float | None = None  # seconds, when given so
        self.next = 0

    def next_step(self, sim: Simulation) -> int | None:
        return self.next if sim._writer is not None else None

    def interval(self, dt: float) -> int:
        """The interval in steps at time step ``dt``."""
        if self.every_s is not None:
            return max(1, round(self.every_s / dt))
        return int(self.every)

    def set(self, every: float | None, every_steps: int | None) -> None:
        self.every_s = every
        self.every = None if every is not None else int(every_steps)

    def first(self, sim: Simulation) -> None:
        """A new file: its interval from dt, the next frame on the interval's multiples."""
        self.every = self.interval(sim.dt)
        self.next = (sim.step_count // self.every + 1) * self.every

    def restart_from_here(self, sim: Simulation) -> None:
        """The interval changed while a file is written: the next frame one interval on."""
        self.every = self.interval(sim.dt)
        self.next = sim.step_count + self.every

    def dt_changed(self, sim: Simulation) -> None:
        if self.every_s is not None and sim._writer is not None:
            self.restart_from_here(sim)

    def run(self, sim: Simulation) -> None:
        self.next += self.every
        sim._write_frame()


class BoundarySwitches(Operation):
    """Boundaries switched off or on at given times (:meth:`dpm.Simulation.switch_off`,
    :mod:`dpm.switches`): ``pending`` (by time) are applied at the step whose end reaches
    their time."""

    order = 40

    def __init__(self) -> None:
        self.pending: list = []

    def next_step(self, sim: Simulation) -> int | None:
        from . import switches

        return switches.next_step(sim)

    def start(self, sim: Simulation) -> None:
        if self.pending:
            from . import switches

            switches.apply_due(sim)  # (dt may have changed since they were scheduled)

    def run(self, sim: Simulation) -> None:
        from . import switches

        switches.apply_due(sim)


class Callback(Operation):
    """The script's own operation: ``function(sim)`` called between kernel calls at the
    steps its trigger fires (``every_steps=N``: every N steps from step 0; or
    ``trigger=dpm.Periodic(N, phase)``), after the built-in operations due there.
    ``needs_host=False`` skips bringing the host state up first (a callback that reads
    nothing of the bodies)."""

    def __init__(self, function: Callable[[Simulation], Any], every_steps: int | None = None,
                 trigger: Trigger | None = None, needs_host: bool = True) -> None:
        if not callable(function):
            raise ParameterError(f"Callback(): function={function!r} is not callable")
        if (every_steps is None) == (trigger is None):
            raise ParameterError("Callback(): give exactly one of every_steps or trigger")
        if trigger is None:
            trigger = Periodic(every_steps)
        elif not isinstance(trigger, Trigger):
            raise ParameterError(f"Callback(): trigger={trigger!r}; allowed: a dpm Trigger "
                                 "(dpm.Periodic(...))")
        self.function = function
        self.trigger = trigger
        self.needs_host = bool(needs_host)  # (an instance's choice)
        self.next: int | None = None

    def next_step(self, sim: Simulation) -> int | None:
        if self.next is None or self.next <= sim.step_count - 1:
            self.next = self.trigger.next(sim.step_count)
        return self.next

    def run(self, sim: Simulation) -> None:
        self.next = self.trigger.next(sim.step_count)
        self.function(sim)

    def __repr__(self) -> str:
        name = getattr(self.function, "__qualname__", repr(self.function))
        return f"Callback({name}, trigger={self.trigger!r})"


class Operations:
    """A simulation's operations (``sim.operations``): the built-in ones by name
    (``sort``, ``flow``, ``frames``, ``switches``, ``checkpoints``: the periodic
    checkpoints' schedule, None while off) and the script's own; iterating gives them in
    the order they run at one step."""

    def __init__(self) -> None:
        self.sort = CellSort()
        self.flow = FlowEvents()
        self.frames = Frames()
        self.switches = BoundarySwitches()
        self.checkpoints: Operation | None = None
        self._added: list[Operation] = []

    def add(self, op: Operation) -> Operation:
        """Add the script's own operation (a :class:`Callback`, or an :class:`Operation`
        subclass); returns it."""
        if not isinstance(op, Operation) or isinstance(op, CellSort | FlowEvents | Frames
                                                         | BoundarySwitches):
            raise ParameterError(f"sim.operations.add(): {op!r} is not an operation of "
                                 "the script's; allowed: a dpm.Callback or an instance of "
                                 "an Operation subclass")
        if any(o is op for o in self._added):
            raise ParameterError(f"sim.operations.add(): {op!r} was added already")
        self._added.append(op)
        return op

    def remove(self, op: Operation) -> None:
        """Take away an operation the script added."""
        for k, o in enumerate(self._added):
            if o is op:
                del self._added[k]
                return
        raise ParameterError(f"sim.operations.remove(): {op!r} is not one the script added")

    def __iter__(self) -> Iterator[Operation]:
        built_in = [self.sort, self.flow, self.frames, self.switches]
        if self.checkpoints is not None:
            built_in.append(self.checkpoints)
        # (a stable sort: the script's own, at equal order, in the order added)
        return iter(sorted(built_in + self._added, key=lambda op: op.order))

    def __len__(self) -> int:
        return 4 + (self.checkpoints is not None) + len(self._added)

    def due_steps(self, sim: Simulation) -> list[int]:
        """The steps at which an operation is next due: a kernel call ends there."""
        return [s for s in (op.next_step(sim) for op in self) if s is not None]

    def start(self, sim: Simulation) -> None:
        for op in self:
            op.start(sim)

    def dt_changed(self, sim: Simulation) -> None:
        for op in self:
            op.dt_changed(sim)

    def run_due(self, sim: Simulation, sync: Callable[[], Any]) -> None:
        """Run, in order, every operation due at this step (``sync`` brings the host
        state up before those that need it)."""
        for op in self:
            due = op.next_step(sim)
            if due is not None and sim.step_count >= due:
                if op.needs_host:
                    sync()
                op.run(sim)
