"""vrneural's own warnings print as one line on stderr: ``warning: <message>``.

Python's default format adds the file, line number and source line of the ``warnings.warn``
call: two lines about vrneural's code instead of the user's input. :class:`VrnWarning` is the
base of every vrneural warning category (a :class:`UserWarning`, so filters on UserWarning still
match them). Importing this module wraps ``warnings.formatwarning`` once
(:func:`install_warning_format`): categories derived from :class:`VrnWarning` format as
``warning: <message>``, every other warning keeps the format it had. The categories import this
module, so the format is in place wherever one of them can be raised. ``formatwarning`` (not
``showwarning``) is wrapped because ``warnings.catch_warnings`` restores ``showwarning`` on exit
but leaves ``formatwarning`` alone, so an import inside such a block keeps the format.
"""

from __future__ import annotations

import warnings


class VrnWarning(UserWarning):
    """Base of vrneural's warning categories: printed as one line, ``warning: <message>``."""


def install_warning_format() -> None:
    """Wrap ``warnings.formatwarning`` so :class:`VrnWarning` categories print as one line
    (idempotent: a second call changes nothing)."""
    previous = warnings.formatwarning
    if getattr(previous, "_vrneural", False):
        return

    def formatwarning(message, category, filename, lineno, line=None):
        if isinstance(category, type) and issubclass(category, VrnWarning):
            return f"warning: {' '.join(str(message).splitlines())}\n"
        return previous(message, category, filename, lineno, line)

    formatwarning._vrneural = True  # type: ignore[attr-defined]
    warnings.formatwarning = formatwarning


install_warning_format()
