import sys

from vrneural.cli import main

if __name__ == "__main__":
    sys.exit(main())
