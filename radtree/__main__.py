"""``python -m radtree``: the same as the ``radtree`` command."""

from radtree.cli import main

main()
