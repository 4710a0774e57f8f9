"""``python -m posekit ...`` (and ``torchrun -m posekit train ...``): the ``posekit`` command."""

import sys

from .cli import main

sys.exit(main())
