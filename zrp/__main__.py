import sys

from zrp.cli.app import main

sys.exit(main())
