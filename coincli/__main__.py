"""`coin` (the console script) and `python -m coincli`."""

import sys


def main() -> None:
    """`coin` on this process's command line. A sweep with a live recording has its
    recording's process started first of all, before the command line's parser and the
    commands are imported (:func:`coincli.io.sweep_recording.start_early`)."""
    from .io.sweep_recording import start_early

    start_early(sys.argv[1:])
    from .cli import main as run_cli

    run_cli()


if __name__ == "__main__":
    main()
