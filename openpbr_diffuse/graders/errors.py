"""The one error a grader raises when a piece it needs is missing."""


class GraderUnavailable(OSError):
    """A runner cannot run: a missing library, compiler, GL driver, source file or a compile error.

    The message is one line naming the missing piece and how to install or point at it; the
    CLI prints it and exits 2.  It is an ``OSError`` (the environment lacks something), which
    ``openpbr-diffuse`` turns into one line on stderr and exit status 2.
    """
