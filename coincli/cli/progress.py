"""The progress bar and column the commands share (rich.progress is imported only by commands
that draw a progress bar, not by `coin --help`)."""

from rich.progress import Progress, ProgressColumn
from rich.text import Text

from .text import clock


class Bars(Progress):
    """rich's Progress, except that stopping one that never showed a bar prints nothing (rich
    prints an empty line when stderr is not a terminal, which would come before an error)."""

    def stop(self) -> None:
        if not self.live.is_started:
            return
        if not self.tasks:
            self.live.stop()
            return
        super().stop()


class RateColumn(ProgressColumn):
    """Items per second: the finished speed, or the running one."""

    def __init__(self, unit: str):
        super().__init__()
        self.unit = unit

    def render(self, task) -> Text:
        speed = task.finished_speed or task.speed
        return Text(f"{speed:,.0f} {self.unit}/s" if speed else f"- {self.unit}/s",
                    style="progress.data.speed")


class CompileClock(ProgressColumn):
    """The time a compilation has taken against the time it is expected to take: '0:42 of
    about 2:00', and past it '2:15 of about 2:00 (a busy machine)'."""

    def __init__(self, expected: float):
        super().__init__()
        self.expected = expected

    def render(self, task) -> Text:
        elapsed = task.elapsed or 0.0
        expected = clock(self.expected)
        text = f"{clock(elapsed)} of about {expected}" + (
            "" if elapsed < self.expected else " (a busy machine)")
        return Text(text, style="progress.elapsed")
