"""Exceptions of the vdbwrap client. Every one carries the server's error kind when there is one."""
import grpc

from vdbwrap.v1 import jobs_pb2 as pb

# The trailing metadata in which the server names the ErrorKind of a failed call.
ERROR_KIND_METADATA = "vdbwrap-error-kind"


def kind_name(value):
    """'INVALID_ARGUMENT' for ERROR_KIND_INVALID_ARGUMENT (2); None for 0 or an unknown number."""
    try:
        value = int(value)
        return pb.ErrorKind.Name(value)[len("ERROR_KIND_"):] if value else None
    except (ValueError, TypeError):
        return None


class VdbwrapError(Exception):
    """A call or a job failed.

    kind: the server's ErrorKind without its prefix ("INVALID_ARGUMENT", "INVALID_INPUT",
          "WRAP_FAILED", ...), or None when the server gave none (e.g. an unknown job id).
    exit_code: the ErrorKind's number, which is the command line's exit code (1 when unknown).
    code: the gRPC status code's name ("INVALID_ARGUMENT", "NOT_FOUND", ...), or None.
    job_id: the job concerned, when known.
    """

    def __init__(self, message, kind=None, code=None, job_id=None):
        super().__init__(message)
        self.message = message
        self.kind = kind
        self.code = code
        self.job_id = job_id

    @property
    def exit_code(self):
        if self.kind is None:
            return 1
        number = pb.ErrorKind.Value("ERROR_KIND_" + self.kind)
        return number if 1 <= number <= 6 else 1

    def __str__(self):
        prefix = self.code or self.kind
        return "%s: %s" % (prefix, self.message) if prefix else self.message


class ParameterError(VdbwrapError, ValueError):
    """Bad wrap parameters: an unknown name (suggestion holds the closest valid one), a value
    of the wrong type, or one the server refused as out of range."""

    def __init__(self, message, suggestion=None, code=None, job_id=None):
        super().__init__(message, kind="INVALID_ARGUMENT", code=code, job_id=job_id)
        self.suggestion = suggestion


class InputError(VdbwrapError):
    """The server refused the mesh (unreadable, or unusable)."""


class NotFoundError(VdbwrapError, LookupError):
    """No job with this id on the server."""


class AuthenticationError(VdbwrapError):
    """Missing or wrong bearer token."""


class JobError(VdbwrapError):
    """A job ended FAILED or CANCELLED. report: its JSON report as a dict when the server kept
    one (a leak: its location and path), else None."""

    def __init__(self, message, kind=None, job_id=None, state=None, report=None):
        super().__init__(message, kind=kind, job_id=job_id)
        self.state = state
        self.report = report

    def __str__(self):
        return "job %s %s (%s): %s" % (self.job_id, self.state, self.kind, self.message)


def from_rpc_error(error, job_id=None):
    """The exception for a failed gRPC call, typed by its ErrorKind and status code."""
    code = error.code() if hasattr(error, "code") else None
    details = error.details() if hasattr(error, "details") else str(error)
    metadata = error.trailing_metadata() if hasattr(error, "trailing_metadata") else None
    kind = None
    for key, value in metadata or ():
        if key == ERROR_KIND_METADATA:
            kind = kind_name(value)
    code_name = code.name if code is not None else None
    if kind == "INVALID_ARGUMENT":
        return ParameterError(details, code=code_name, job_id=job_id)
    if kind == "INVALID_INPUT":
        return InputError(details, kind=kind, code=code_name, job_id=job_id)
    if code == grpc.StatusCode.NOT_FOUND:
        return NotFoundError(details, kind=kind, code=code_name, job_id=job_id)
    if code == grpc.StatusCode.UNAUTHENTICATED:
        return AuthenticationError(details, kind=kind, code=code_name, job_id=job_id)
    return VdbwrapError(details, kind=kind, code=code_name, job_id=job_id)
