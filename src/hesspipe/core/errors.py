"""The one exception type for user mistakes and unmet conditions.

Anything raised as :class:`HesspipeError` is shown by the CLI as a single
line (``hesspipe: error: <message>``) with a non-zero exit status, never as
a traceback. Messages name the file, the field and what was expected.
"""


class HesspipeError(Exception):
    """A user-facing error: bad input, an impossible condition, a failed trim.

    Parameters
    ----------
    message : str
        One line: what was wrong, where (file, field), and what was expected.
    """

    def __init__(self, message: str):
        super().__init__(" ".join(str(message).split()))


def where(path, field=None) -> str:
    """Return ``"path: field 'x'"`` for error messages.

    Parameters
    ----------
    path : str or Path
        The file the message is about.
    field : str, optional
        The field inside it.
    """
    out = str(path)
    if field:
        out += f": field '{field}'"
    return out


def reason(exc: BaseException) -> str:
    """The first line of a library's exception, for a one-line message about an unreadable file.

    Parameters
    ----------
    exc : BaseException
        What the reading library raised.

    Returns
    -------
    str
        Its message's first line, at most 80 characters; its type's name where it has no message.
    """
    lines = str(exc).strip().splitlines()
    return lines[0][:80] if lines else type(exc).__name__
