import sys

from weldplan.cli import main

sys.exit(main())
