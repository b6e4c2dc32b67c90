"""``python -m twin.cli``: the command line, as the ``twin`` script runs it."""

from twin.cli import main

main()
