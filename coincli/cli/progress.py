"""The progress bar and column the commands share (rich.progress is imported only by commands
that draw a progress bar, not by `coin --help`)."""

from rich.progress import Progress, ProgressColumn
from rich.text import Text


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
