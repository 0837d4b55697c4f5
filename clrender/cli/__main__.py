"""`python -m clrender.cli ...`: the `clrender` command."""
import sys

from .app import main

sys.exit(main())
