#!/usr/bin/env python3
"""A fenestrad client written from the .proto files alone: registers a site (the scene's
outdoor part, whose outdoor matrix the daemon computes once and caches), submits a job on
it and prints its progress and best design.

The stubs are generated at run time into a temporary folder, from proto/fenestra/v1. It
needs python3-grpcio and python3-protobuf, and a protoc with the gRPC Python plugin:
Debian's protoc (protobuf-compiler) with grpc_python_plugin (protobuf-compiler-grpc) is
used when present, else grpc_tools.protoc (python3-grpc-tools; Debian 12's is too old for
proto3 `optional` fields, hence the order).

  /usr/bin/python3 examples/python_client.py --server localhost:50051 \
      examples/city_office/alpha_max_quick.json

Security, as in the fenestra command: --tls-ca CA.pem turns TLS on and verifies the
daemon's certificate with that CA (--tls-cert/--tls-key add a client certificate); the
bearer token comes from --token-file, else the FENESTRA_TOKEN environment variable, and
goes with every request as `authorization: Bearer <token>` metadata.
"""
import argparse
import importlib
import os
import shutil
import subprocess
import sys
import tempfile
import time

import grpc

REPO = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
PROTO_DIR = os.path.join(REPO, "proto")
PROTOS = ["fenestra/v1/scene.proto", "fenestra/v1/job.proto", "fenestra/v1/service.proto"]
TOKEN_VARIABLE = "FENESTRA_TOKEN"


def generate_stubs(out_dir):
    """Writes fenestra/v1/*_pb2.py and *_pb2_grpc.py into out_dir and imports them."""
    protoc, plugin = shutil.which("protoc"), shutil.which("grpc_python_plugin")
    args = ["-I", PROTO_DIR, "--python_out", out_dir, "--grpc_python_out", out_dir] + PROTOS
    if protoc and plugin:
        subprocess.run([protoc, "--plugin=protoc-gen-grpc_python=" + plugin] + args, check=True)
    else:
        from grpc_tools import protoc as grpc_protoc
        if grpc_protoc.main(["protoc"] + args) != 0:
            sys.exit("error: cannot generate the Python stubs from " + PROTO_DIR)
    sys.path.insert(0, out_dir)
    return (importlib.import_module("fenestra.v1.job_pb2"),
            importlib.import_module("fenestra.v1.scene_pb2"),
            importlib.import_module("fenestra.v1.service_pb2"),
            importlib.import_module("fenestra.v1.service_pb2_grpc"))


def fail(message):
    sys.exit(f"error: {message}")


def read_file(flag, path):
    """The bytes of the file given to `flag`; exits naming both when it cannot be read."""
    try:
        with open(path, "rb") as f:
            return f.read()
    except OSError as e:
        fail(f"{flag} {path}: cannot open ({e.strerror})")


def load_token(token_file):
    """The bearer token from token_file, else FENESTRA_TOKEN, without surrounding whitespace;
    None when neither is given. The token itself never appears in an error."""
    if token_file:
        source, token = f"--token-file {token_file}", read_file("--token-file", token_file)
    elif TOKEN_VARIABLE in os.environ:
        source, token = TOKEN_VARIABLE, os.environb[TOKEN_VARIABLE.encode()]
    else:
        return None
    token = token.strip()
    if not token:
        fail(f"{source}: the token is empty")
    for i, byte in enumerate(token):
        if not 0x21 <= byte <= 0x7e:  # a header value is visible ASCII
            fail(f"{source}: the token's character {i + 1} cannot go in a request header "
                 "(only visible ASCII, no spaces)")
    return token.decode("ascii")


def open_channel(args):
    """A channel to fenestrad: TLS verified with --tls-ca when given, else plaintext."""
    options = [("grpc.keepalive_time_ms", 30000), ("grpc.max_receive_message_length", 1 << 28)]
    if bool(args.tls_cert) != bool(args.tls_key):
        fail("--tls-cert and --tls-key go together (the client certificate and its private key)")
    if not args.tls_ca:
        if args.tls_cert:
            fail("--tls-cert needs --tls-ca (the CA that signed fenestrad's certificate)")
        return grpc.insecure_channel(args.server, options=options)
    credentials = grpc.ssl_channel_credentials(
        root_certificates=read_file("--tls-ca", args.tls_ca),
        private_key=read_file("--tls-key", args.tls_key) if args.tls_key else None,
        certificate_chain=read_file("--tls-cert", args.tls_cert) if args.tls_cert else None)
    return grpc.secure_channel(args.server, credentials, options=options)


def is_local(target):
    """Whether a gRPC target ("host:port", "dns:///host:port", "unix:path") is this machine."""
    if target.startswith("unix:"):
        return True
    host = target.removeprefix("dns:///").removeprefix("ipv4:").removeprefix("ipv6:")
    host = host.rsplit(":", 1)[0]
    return host in ("localhost", "[::1]") or host.startswith("127.")


def error_text(error, args, token):
    """What a failed call tells the user."""
    code, details = error.code(), error.details()
    if code == grpc.StatusCode.UNAVAILABLE and "handshake" in details.lower():
        return (f"cannot reach fenestrad at {args.server}: the TLS handshake failed ({details}); "
                "does it serve TLS with a certificate signed by the --tls-ca CA?")
    if code == grpc.StatusCode.UNAVAILABLE:
        return f"cannot reach fenestrad at {args.server} ({details}); is it running?"
    if code == grpc.StatusCode.DEADLINE_EXCEEDED:
        return f"fenestrad at {args.server} did not answer within {args.timeout:g} s (--timeout)"
    if code == grpc.StatusCode.UNAUTHENTICATED:
        refused = "refused the token" if token else "wants a token"
        return f"fenestrad {refused} ({details}): set --token-file or {TOKEN_VARIABLE}"
    return f"{code.name}: {details}"


def design_text(design, finishes=()):
    """name=value per variable; the finish (an index into the job's list) by its materials."""
    def value(name):
        if name == "finish" and finishes:
            f = finishes[int(design[name])]
            outer = f" / {f.outer_material} outer" if f.HasField("outer_material") else ""
            return f.material + outer
        return f"{design[name]:.4g}"
    return " ".join(f"{name}={value(name)}" for name in sorted(design))


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("job", nargs="?",
                        default=os.path.join(REPO, "examples/city_office/alpha_max_quick.json"),
                        help="job file (JSON); its scene_file and weather file are sent inline")
    parser.add_argument("--server", default="localhost:50051", help="fenestrad host:port")
    parser.add_argument("--timeout", type=float, default=30, help="deadline per request [s]")
    parser.add_argument("--tls-ca", help="use TLS; verify fenestrad's certificate with this CA")
    parser.add_argument("--tls-cert", help="client certificate (PEM) for mTLS, with --tls-key")
    parser.add_argument("--tls-key", help="private key of the client certificate (PEM)")
    parser.add_argument("--token-file",
                        help=f"bearer token sent with every request; default: ${TOKEN_VARIABLE}")
    parser.add_argument("--outdoor-paths", type=int, help="override sampling.outdoor_paths")
    parser.add_argument("--indoor-paths", type=int,
                        help="override sampling.indoor_paths_per_sensor")
    parser.add_argument("--evaluations", type=int, help="override budget.max_evaluations")
    args = parser.parse_args()
    token = load_token(args.token_file)
    if token and not args.tls_ca and not is_local(args.server):
        print(f"warning: the token goes to {args.server} unencrypted; give --tls-ca to use TLS",
              file=sys.stderr)
    # The token goes with every call, the deadline with every call but Watch (a stream)
    metadata = [("authorization", f"Bearer {token}")] if token else None
    unary = {"timeout": args.timeout, "metadata": metadata}

    with tempfile.TemporaryDirectory() as stubs:
        job_pb2, scene_pb2, service_pb2, service_grpc = generate_stubs(stubs)
        from google.protobuf import json_format

        # The job, its scene and its weather file, read here and sent inline
        job_dir = os.path.dirname(os.path.abspath(args.job))
        with open(args.job) as f:
            job = json_format.Parse(f.read(), job_pb2.Job())
        scene_dir = job_dir
        if job.scene_file:
            scene_path = os.path.join(job_dir, job.scene_file)
            with open(scene_path) as f:
                job.scene.CopyFrom(json_format.Parse(f.read(), scene_pb2.Scene()))
            scene_dir = os.path.dirname(scene_path)
            job.scene_file = ""
        if any(s.HasField("obj") for s in job.scene.surfaces):
            sys.exit("error: this example sends no OBJ meshes; use `fenestra job submit`")
        weather = (os.path.join(job_dir, job.weather_file) if job.weather_file
                   else os.path.join(scene_dir, job.scene.site.weather_file))
        with open(weather, "rb") as f:
            weather_epw = f.read()
        job.weather_file = ""
        job.scene.site.weather_file = ""
        if args.outdoor_paths:
            job.sampling.outdoor_paths = args.outdoor_paths
        if args.indoor_paths:
            job.sampling.indoor_paths_per_sensor = args.indoor_paths
        if args.evaluations:
            job.budget.max_evaluations = args.evaluations
        finishes = next((v.finishes for v in job.variables if v.name == "finish"), ())

        channel = open_channel(args)
        sites = service_grpc.SiteServiceStub(channel)
        jobs = service_grpc.JobServiceStub(channel)
        try:
            # A site: the outdoor matrix is computed once, in the background
            site = sites.Register(service_pb2.RegisterSiteRequest(
                name=job.scene.name, scene=job.scene, sampling=job.sampling,
                weather_epw=weather_epw, weather_name=os.path.basename(weather)), **unary)
            print(f"{site.id} registered", flush=True)
            while site.state == service_pb2.SITE_STATE_COMPUTING:
                time.sleep(0.25)
                site = sites.Get(service_pb2.GetSiteRequest(id=site.id), **unary)
            if site.state != service_pb2.SITE_STATE_READY:
                sys.exit(f"error: {site.id} failed: {site.error}")
            print(f"{site.id} ready: outdoor matrix traced in {site.compute_seconds:.2f} s, "
                  f"mean relative standard error {site.mean_relative_standard_error:.4f}",
                  flush=True)

            # The job on that site, and its events
            info = jobs.Submit(service_pb2.SubmitJobRequest(job=job, site_id=site.id), **unary)
            print(f"{info.id} submitted", flush=True)
            for event in jobs.Watch(service_pb2.WatchJobRequest(id=info.id), metadata=metadata):
                kind = event.WhichOneof("kind")
                if kind == "snapshot":
                    print(f"{info.id}: {service_pb2.JobState.Name(event.snapshot.state)}")
                elif kind == "stage":
                    cached = " (cached)" if event.stage.cached else ""
                    print(f"stage {event.stage.name}{cached}")
                elif kind == "progress":
                    p = event.progress
                    print(f"[{p.evaluations}/{p.max_evaluations}] best "
                          f"{p.best.value.value:.2f} ± {p.best.value.standard_error:.2f} % "
                          f"({design_text(p.best.design, finishes)}) | current "
                          f"{p.current.value.value:.2f} % ({design_text(p.current.design, finishes)})",
                          flush=True)
                elif kind == "finished":
                    r = event.finished
                    print(f"best design: {design_text(r.best_design, finishes)}\n"
                          f"objective: {r.best_value.value:.2f} ± "
                          f"{r.best_value.standard_error:.2f} % after {r.evaluations} "
                          f"evaluations ({r.stop_reason})")
                    return 0
                elif kind in ("failed", "cancelled", "interrupted"):
                    reason = f": {event.failed}" if kind == "failed" else ""
                    print(f"{info.id} {kind}{reason}", file=sys.stderr)
                    return 1
            print("error: the event stream ended early", file=sys.stderr)
            return 1
        except grpc.RpcError as e:
            fail(error_text(e, args, token))


if __name__ == "__main__":
    sys.exit(main())
