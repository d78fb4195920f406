import sys

from zrp.cli.main import main

sys.exit(main())
