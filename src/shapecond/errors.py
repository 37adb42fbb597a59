"""Error types shared by the library and the command line.

``InputError`` (a ``ValueError``) is raised for anything wrong with what the
user gave us (a broken mesh, landmarks out of range, a non-square distance
matrix, an option out of range...); ``OutputError`` (an ``OSError``) for a
result that cannot be written (a full disk, a read-only folder, a link or FIFO
where a file should go).  Both derive from ``ShapecondError``; the command line
turns either into one ``error: ...`` line on stderr and exit status 2.  Any
other exception is an internal failure (exit status 1).
"""


class ShapecondError(Exception):
    """Base class of the errors raised on purpose by shapecond."""


class InputError(ShapecondError, ValueError):
    """The user's input cannot be used; the message says why in one line."""


class TooLargeError(InputError):
    """A computation was refused because its estimated time or memory exceeds a limit.

    The message gives the estimate and the option (``--force``, or ``force=True``)
    that runs it anyway.
    """


class OutputError(ShapecondError, OSError):
    """An output file cannot be written (full disk, no permission, a folder in the way)."""
