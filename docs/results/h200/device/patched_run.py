"""`vrneural run` with the eye targets' depth format replaced (argv[1]) for an A/B."""
import sys

from vrneural.runtime import forward

forward.DEPTH_FORMAT = sys.argv.pop(1)
from vrneural.cli import main  # noqa: E402

sys.exit(main(sys.argv[1:]))
