"""The progress column the sweep commands share (rich.progress is imported only by commands
that draw a progress bar, not by `coin --help`)."""

from rich.progress import ProgressColumn
from rich.text import Text


class RateColumn(ProgressColumn):
    """Items per second: the finished speed, or the running one."""

    def __init__(self, unit: str):
        super().__init__()
        self.unit = unit

    def render(self, task) -> Text:
        speed = task.finished_speed or task.speed
        return Text(f"{speed:,.0f} {self.unit}/s" if speed else f"- {self.unit}/s",
                    style="progress.data.speed")
