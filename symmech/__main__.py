import sys

from symmech.cli import main

sys.exit(main())
