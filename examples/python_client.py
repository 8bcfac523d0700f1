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

A daemon with TLS and tokens (the default beyond loopback) needs --tls-ca (the CA file
that signed the server's certificate) and a token (--token-file, or FENESTRA_TOKEN), sent
as "authorization: Bearer <token>" with every call.
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


def design_text(design):
    return " ".join(f"{name}={design[name]:.4g}" for name in sorted(design))


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("job", nargs="?",
                        default=os.path.join(REPO, "examples/city_office/alpha_max_quick.json"),
                        help="job file (JSON); its scene_file and weather file are sent inline")
    parser.add_argument("--server", default="localhost:50051", help="fenestrad host:port")
    parser.add_argument("--timeout", type=float, default=30, help="deadline per request [s]")
    parser.add_argument("--outdoor-paths", type=int, help="override sampling.outdoor_paths")
    parser.add_argument("--indoor-paths", type=int,
                        help="override sampling.indoor_paths_per_sensor")
    parser.add_argument("--evaluations", type=int, help="override budget.max_evaluations")
    parser.add_argument("--tls-ca", help="connect with TLS, trusting this CA file (PEM)")
    parser.add_argument("--token-file", help="file holding the token (default: $FENESTRA_TOKEN)")
    args = parser.parse_args()
    token = os.environ.get("FENESTRA_TOKEN", "")
    if args.token_file:
        with open(args.token_file) as f:
            token = f.read().strip()
    metadata = [("authorization", "Bearer " + token)] if token else []

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

        options = [("grpc.keepalive_time_ms", 30000),
                   ("grpc.max_receive_message_length", 1 << 28)]
        if args.tls_ca:
            with open(args.tls_ca, "rb") as f:
                credentials = grpc.ssl_channel_credentials(root_certificates=f.read())
            channel = grpc.secure_channel(args.server, credentials, options=options)
        else:
            channel = grpc.insecure_channel(args.server, options=options)
        sites = service_grpc.SiteServiceStub(channel)
        jobs = service_grpc.JobServiceStub(channel)
        try:
            # A site: the outdoor matrix is computed once, in the background
            site = sites.Register(service_pb2.RegisterSiteRequest(
                name=job.scene.name, scene=job.scene, sampling=job.sampling,
                weather_epw=weather_epw, weather_name=os.path.basename(weather)),
                timeout=args.timeout, metadata=metadata)
            print(f"{site.id} registered", flush=True)
            while site.state == service_pb2.SITE_STATE_COMPUTING:
                time.sleep(0.25)
                site = sites.Get(service_pb2.GetSiteRequest(id=site.id), timeout=args.timeout,
                                 metadata=metadata)
            if site.state != service_pb2.SITE_STATE_READY:
                sys.exit(f"error: {site.id} failed: {site.error}")
            print(f"{site.id} ready: outdoor matrix traced in {site.compute_seconds:.2f} s, "
                  f"mean relative standard error {site.mean_relative_standard_error:.4f}",
                  flush=True)

            # The job on that site, and its events
            info = jobs.Submit(service_pb2.SubmitJobRequest(job=job, site_id=site.id),
                               timeout=args.timeout, metadata=metadata)
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
                          f"({design_text(p.best.design)}) | current "
                          f"{p.current.value.value:.2f} % ({design_text(p.current.design)})",
                          flush=True)
                elif kind == "finished":
                    r = event.finished
                    print(f"best design: {design_text(r.best_design)}\n"
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
            if e.code() == grpc.StatusCode.UNAVAILABLE:
                sys.exit(f"error: cannot reach fenestrad at {args.server} ({e.details()})")
            sys.exit(f"error: {e.code().name}: {e.details()}")


if __name__ == "__main__":
    sys.exit(main())
