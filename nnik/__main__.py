import sys

from nnik.cli import main

sys.exit(main())
