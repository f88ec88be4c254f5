"""``python -m imukit``: the same as the ``imukit`` command."""

from imukit.cli import main

raise SystemExit(main())
