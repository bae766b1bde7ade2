"""The one error a grader raises when a piece it needs is missing."""


class GraderUnavailable(Exception):
    """A runner cannot run: a missing library, compiler, GL driver, source file or a compile error.

    The message is one line naming the missing piece and how to install or point at it; the
    CLI prints it and exits 2.
    """
