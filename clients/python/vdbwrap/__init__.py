"""Python client of the vdbwrap job service (gRPC API vdbwrap.v1, proto/vdbwrap/v1/jobs.proto).

    import vdbwrap
    with vdbwrap.Client("127.0.0.1:50051", token="...") as client:
        result = client.wrap("part.stl", "part_wrap.stl", base_size_percent=1, levels=2)
"""
from vdbwrap.client import Client, Job, Progress, WrapResult
from vdbwrap.errors import (AuthenticationError, InputError, JobError, NotFoundError, ParameterError,
                            VdbwrapError)
from vdbwrap.params import load_file, wrap_parameters

__version__ = "0.1.0"

__all__ = ["Client", "Job", "Progress", "WrapResult", "VdbwrapError", "ParameterError", "InputError",
           "NotFoundError", "AuthenticationError", "JobError", "wrap_parameters", "load_file"]
