"""vdbwrap.Client: submits meshes to a vdbwrap job server, follows the jobs and fetches the results."""
import json
import os
import uuid
from dataclasses import dataclass
from typing import Iterator, List, Optional

import grpc

from vdbwrap.errors import JobError, VdbwrapError, from_rpc_error, kind_name
from vdbwrap.params import wrap_parameters
from vdbwrap.v1 import jobs_pb2 as pb
from vdbwrap.v1 import jobs_pb2_grpc as pb_grpc

CHUNK = 1 << 20  # the API's advice for Submit chunks; a message may not exceed 4 MiB

# Output formats by file extension (the command line's writers).
FORMATS = {
    ".stl": pb.MESH_FORMAT_STL,
    ".obj": pb.MESH_FORMAT_OBJ,
    ".off": pb.MESH_FORMAT_OFF,
    ".ply": pb.MESH_FORMAT_PLY,
    ".vtp": pb.MESH_FORMAT_VTP,
    ".nas": pb.MESH_FORMAT_NASTRAN,
    ".bdf": pb.MESH_FORMAT_NASTRAN,
}

FINAL_STATES = ("succeeded", "failed", "cancelled")


def _state(value):
    return pb.JobState.Name(value)[len("JOB_STATE_"):].lower()


@dataclass(frozen=True)
class Progress:
    """One event of Watch. state: "queued", "running", "succeeded", "failed" or "cancelled"."""

    sequence: int
    state: str
    stage: str
    fraction: float
    message: str
    elapsed_seconds: float
    error_kind: Optional[str]
    error_message: str

    @property
    def final(self):
        return self.state in FINAL_STATES

    @classmethod
    def from_pb(cls, ev):
        return cls(ev.sequence, _state(ev.state), ev.stage, ev.fraction, ev.message, ev.elapsed_seconds,
                   kind_name(ev.error_kind), ev.error_message)


@dataclass(frozen=True)
class Job:
    """A job's status (GetStatus, Cancel, List). report: the JSON report as a dict (GetStatus of
    an ended job), else None."""

    job_id: str
    state: str
    file_name: str
    stage: str
    fraction: float
    error_kind: Optional[str]
    error_message: str
    report: Optional[dict]
    output_triangles: int
    result_bytes: int
    raw: pb.JobStatus

    @classmethod
    def from_pb(cls, st):
        report = None
        if st.report_json:
            try:
                report = json.loads(st.report_json)
            except ValueError:
                report = None
        return cls(st.job_id, _state(st.state), st.spec.file_name, st.stage, st.fraction, kind_name(st.error_kind),
                   st.error_message, report, st.output_triangles, st.result_bytes, st)


@dataclass(frozen=True)
class WrapResult:
    """What Client.wrap produced: the downloaded file, the job and its JSON report."""

    job_id: str
    output: str
    report: Optional[dict]
    output_triangles: int


class Client:
    """A connection to a vdbwrap-server.

    address: "host:port". token: the server's bearer token (--token-file), if it has one.
    tls_ca: PEM bytes or a file name of the CA that signed the server's certificate (TLS);
    without it the channel is plain text. timeout: seconds for each unary call (Watch and the
    transfers are not limited).
    """

    def __init__(self, address, token=None, tls_ca=None, timeout=60.0):
        if tls_ca is not None:
            if not isinstance(tls_ca, bytes):
                with open(tls_ca, "rb") as f:
                    tls_ca = f.read()
            self._channel = grpc.secure_channel(address, grpc.ssl_channel_credentials(root_certificates=tls_ca))
        else:
            self._channel = grpc.insecure_channel(address)
        self._stub = pb_grpc.JobsStub(self._channel)
        self._metadata = [("authorization", "Bearer " + token.strip())] if token else []
        self._timeout = timeout

    def close(self):
        self._channel.close()

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()

    # --- the calls of the API ---

    def submit(self, path, params=None, output_format=None, idempotency_key=None, **kwargs) -> str:
        """Uploads the mesh at `path` and queues a wrap job; returns its id.

        params: a dict, a JSON/YAML file or a WrapParameters message; keyword arguments (names
        of WrapParameters fields) override it. output_format: an extension (".stl") or a
        MeshFormat; default the input's format.
        """
        message = wrap_parameters(params, **kwargs)  # checked before any upload
        path = os.fspath(path)
        size = os.path.getsize(path)
        spec = pb.JobSpec(file_name=os.path.basename(path), params=message, output_format=_format(output_format),
                          idempotency_key=idempotency_key or str(uuid.uuid4()), size_bytes=size,
                          kind=pb.JOB_KIND_WRAP)

        def requests():
            yield pb.SubmitRequest(spec=spec)
            with open(path, "rb") as f:
                while True:
                    data = f.read(CHUNK)
                    if not data:
                        return
                    yield pb.SubmitRequest(chunk=data)

        try:
            return self._stub.Submit(requests(), metadata=self._metadata).job_id
        except grpc.RpcError as e:
            raise from_rpc_error(e) from None

    def watch(self, job_id) -> Iterator[Progress]:
        """The job's progress events: those so far, then live ones, until it ends (the last
        event has a final state)."""
        try:
            for ev in self._stub.Watch(pb.JobId(job_id=job_id), metadata=self._metadata):
                yield Progress.from_pb(ev)
        except grpc.RpcError as e:
            raise from_rpc_error(e, job_id) from None

    def status(self, job_id) -> Job:
        return Job.from_pb(self._call(self._stub.GetStatus, pb.JobId(job_id=job_id), job_id))

    def download(self, job_id, out, output_format=None) -> str:
        """Writes the result of a succeeded job to `out` (whole or not at all); the format
        follows out's extension unless given. Returns out."""
        out = os.fspath(out)
        fmt = _format(output_format) if output_format is not None else FORMATS.get(os.path.splitext(out)[1].lower(), 0)
        tmp = "%s.%s.part" % (out, uuid.uuid4().hex[:8])
        size, got = None, 0
        try:
            with open(tmp, "wb") as f:
                for chunk in self._stub.Download(pb.DownloadRequest(job_id=job_id, format=fmt), metadata=self._metadata):
                    if size is None:
                        size = chunk.total_size
                    f.write(chunk.data)
                    got += len(chunk.data)
            if size is not None and got != size:
                raise VdbwrapError("download of job %s incomplete (%d of %d bytes)" % (job_id, got, size),
                                   kind="OUTPUT_FAILED", job_id=job_id)
            os.replace(tmp, out)
        except grpc.RpcError as e:
            raise from_rpc_error(e, job_id) from None
        finally:
            if os.path.exists(tmp):
                os.remove(tmp)
        return out

    def cancel(self, job_id) -> Job:
        """Cancels a queued or running job (a no-op for a cancelled one)."""
        return Job.from_pb(self._call(self._stub.Cancel, pb.JobId(job_id=job_id), job_id))

    def delete(self, job_id) -> None:
        """Deletes an ended job and its files."""
        self._call(self._stub.Delete, pb.JobId(job_id=job_id), job_id)

    def jobs(self) -> List[Job]:
        """Every job on the server, oldest first (without reports)."""
        return [Job.from_pb(st) for st in self._call(self._stub.List, pb.ListRequest(), None).jobs]

    # --- one call ---

    def wrap(self, path, out, params=None, on_progress=None, report=None, **kwargs) -> WrapResult:
        """Submits `path`, follows the job until it ends, downloads the result to `out` (its
        extension picks the format). on_progress: called with every Progress. report: a file
        name for the JSON report. Raises JobError when the job fails or is cancelled."""
        out = os.fspath(out)
        fmt = os.path.splitext(out)[1].lower()
        if fmt not in FORMATS:
            raise VdbwrapError("%s: unknown output format (use %s)" % (out, " ".join(sorted(FORMATS))),
                               kind="INVALID_ARGUMENT")
        job_id = self.submit(path, params, output_format=fmt, **kwargs)
        for ev in self.watch(job_id):
            if on_progress is not None:
                on_progress(ev)
        job = self.status(job_id)
        if job.state != "succeeded":
            raise JobError(job.error_message or "the job ended " + job.state, kind=job.error_kind, job_id=job_id,
                           state=job.state, report=job.report)
        self.download(job_id, out)
        if report is not None:
            with open(report, "w", encoding="utf-8") as f:
                f.write(job.raw.report_json)
        return WrapResult(job_id, out, job.report, job.output_triangles)

    def _call(self, method, request, job_id):
        try:
            return method(request, metadata=self._metadata, timeout=self._timeout)
        except grpc.RpcError as e:
            raise from_rpc_error(e, job_id) from None


def _format(value):
    """A MeshFormat from None (unspecified), a number, or an extension / name ("stl", ".stl")."""
    if value is None:
        return pb.MESH_FORMAT_UNSPECIFIED
    if isinstance(value, int):
        return value
    key = "." + str(value).lower().lstrip(".")
    if key in FORMATS:
        return FORMATS[key]
    raise VdbwrapError("unknown mesh format %r (use %s)" % (value, " ".join(sorted(FORMATS))), kind="INVALID_ARGUMENT")
