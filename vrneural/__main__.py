import sys

from vrneural.cli import main

sys.exit(main())
