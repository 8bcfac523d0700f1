#!/usr/bin/python3
"""deploy/kubernetes rendered by `kubectl kustomize` (base and the cpu, gpu and trial
overlays, with secrets made by make-trial-secrets.sh in a copy of the folder) and checked:
the kinds, the GPU request in the gpu overlay alone, gRPC probes on the health port, every
Secret and ConfigMap reference resolving to an object of the render, the ConfigMap's JSON
and the container's flags accepted by `fenestrad --check-config`, fenestrad started as
configured answering the probes, labels and selectors, security contexts and resources.

Usage: kubernetes_test.py --fenestrad PATH --source REPO [unittest options]
Needs kubectl with kustomize 5 (kubectl 1.27 or newer) and Debian's python3-yaml.
"""
import argparse
import base64
import json
import os
import re
import shutil
import subprocess
import sys
import tempfile
import time
import unittest

import yaml

FENESTRAD = ""
SOURCE = ""
RENDERS = ("base", "overlays/cpu", "overlays/gpu", "overlays/trial")
KUSTOMIZE_MAJOR = 5


def run(args, **kwargs):
    return subprocess.run(args, capture_output=True, text=True, timeout=60, **kwargs)


def kustomize_version():
    """kubectl's embedded kustomize as (major, minor), or None without kubectl."""
    if shutil.which("kubectl") is None:
        return None
    out = run(["kubectl", "version", "--client", "-o", "json"])
    found = re.search(r'"kustomizeVersion":\s*"v(\d+)\.(\d+)', out.stdout)
    return (int(found.group(1)), int(found.group(2))) if found else (0, 0)


def pod_spec(workload):
    return workload["spec"]["template"]["spec"]


def containers(spec):
    return spec.get("containers", []) + spec.get("initContainers", [])


def decoded(secret, key):
    if key in secret.get("stringData", {}):
        return secret["stringData"][key]
    return base64.b64decode(secret["data"][key]).decode()


def port_of(address):
    return int(address.rsplit(":", 1)[1])


class Render:
    """The objects one kustomization renders to."""

    def __init__(self, text):
        self.objects = [o for o in yaml.safe_load_all(text) if o]
        self.text = text

    def all(self, kind):
        return [o for o in self.objects if o["kind"] == kind]

    def get(self, kind, name):
        found = [o for o in self.all(kind) if o["metadata"]["name"] == name]
        return found[0] if len(found) == 1 else None

    def workloads(self):
        return self.all("Deployment") + self.all("StatefulSet")

    def fenestrad(self):
        deployment = self.get("Deployment", "fenestrad")
        container = [c for c in pod_spec(deployment)["containers"] if c["name"] == "fenestrad"]
        return deployment, container[0]


class KubernetesManifestsTest(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        version = kustomize_version()
        if version is None or version[0] < KUSTOMIZE_MAJOR:
            raise RuntimeError(
                "kubectl with kustomize %d (kubectl 1.27 or newer) is needed, found %s; "
                "Debian 12's kubernetes-client (kubectl 1.20, kustomize 2.0.3) cannot render "
                "these manifests" % (KUSTOMIZE_MAJOR, version))
        cls.tmp = tempfile.mkdtemp(prefix="kubernetes_test.")
        cls.folder = os.path.join(cls.tmp, "kubernetes")
        # A copy without any secret file a developer may have made in the tree
        shutil.copytree(os.path.join(SOURCE, "deploy", "kubernetes"), cls.folder,
                        ignore=lambda folder, names: [
                            n for n in names
                            if os.path.basename(folder) == "secrets" and n != ".gitignore"])
        cls.without_secrets = run(
            ["kubectl", "kustomize", os.path.join(cls.folder, "overlays/cpu")])
        made = run(["bash", os.path.join(cls.folder, "make-trial-secrets.sh"), "test-ns"])
        if made.returncode != 0:
            raise RuntimeError("make-trial-secrets.sh failed:\n" + made.stderr)
        cls.renders = {}
        for name in RENDERS:
            out = run(["kubectl", "kustomize", os.path.join(cls.folder, name)])
            if out.returncode != 0:
                raise RuntimeError("kubectl kustomize %s failed:\n%s" % (name, out.stderr))
            cls.renders[name] = Render(out.stdout)
        cls.ca = os.path.join(cls.folder, "base", "secrets", "ca.crt")

    @classmethod
    def tearDownClass(cls):
        shutil.rmtree(cls.tmp, ignore_errors=True)

    def test_without_the_secret_files_the_render_stops_naming_them(self):
        self.assertNotEqual(self.without_secrets.returncode, 0)
        self.assertIn("secrets/store.env", self.without_secrets.stderr)

    def test_kinds(self):
        for name, render in self.renders.items():
            with self.subTest(render=name):
                for kind, name_ in [("Deployment", "fenestrad"), ("Service", "fenestrad"),
                                    ("PodDisruptionBudget", "fenestrad")]:
                    self.assertIsNotNone(render.get(kind, name_), kind)
                self.assertEqual(len(render.all("ConfigMap")), 1)
                secrets = {s["metadata"]["name"].rsplit("-", 1)[0] for s in render.all("Secret")}
                trial = name == "overlays/trial"
                self.assertEqual(secrets, {"fenestrad-store", "fenestrad-tls"} |
                                 ({"fenestra-postgresql"} if trial else set()))
                # The trial database only where asked for
                self.assertEqual(len(render.all("StatefulSet")), 1 if trial else 0)
                self.assertEqual(len(render.all("Service")), 2 if trial else 1)

    def test_gpu_request_in_the_gpu_overlay_only(self):
        _, container = self.renders["overlays/gpu"].fenestrad()
        for part in ("requests", "limits"):
            self.assertEqual(int(container["resources"][part]["nvidia.com/gpu"]), 1)
        deployment, _ = self.renders["overlays/gpu"].fenestrad()
        spec = pod_spec(deployment)
        self.assertEqual(spec["nodeSelector"], {"nvidia.com/gpu.present": "true"})
        self.assertIn({"key": "nvidia.com/gpu", "operator": "Exists", "effect": "NoSchedule"},
                      spec["tolerations"])
        # A rollout that needs no spare GPU
        self.assertEqual(deployment["spec"]["strategy"]["rollingUpdate"]["maxSurge"], 0)
        for name in ("base", "overlays/cpu", "overlays/trial"):
            self.assertNotIn("nvidia.com/gpu", self.renders[name].text, name)

    def test_images_and_backends(self):
        dockerfiles = []
        for name in ("Dockerfile.cpu", "Dockerfile.cuda"):
            with open(os.path.join(SOURCE, "docker", name)) as dockerfile:
                dockerfiles.append(dockerfile.read())
        for name, image, backend in [("base", "fenestrad", None),
                                     ("overlays/cpu", "fenestrad:cpu", "cpu"),
                                     ("overlays/trial", "fenestrad:cpu", "cpu"),
                                     ("overlays/gpu", "fenestrad:cuda", "cuda")]:
            with self.subTest(render=name):
                _, container = self.renders[name].fenestrad()
                self.assertEqual(container["image"], image)
                args = container["args"]
                if backend is None:
                    self.assertNotIn("--backend", args)
                else:
                    self.assertEqual(args[args.index("--backend") + 1], backend)
                # The images' binary
                for dockerfile in dockerfiles:
                    self.assertIn('"%s"' % container["command"][0], dockerfile)

    def test_probes_are_grpc_on_the_health_port(self):
        for name, render in self.renders.items():
            with self.subTest(render=name):
                _, container = render.fenestrad()
                ports = {p["name"]: p["containerPort"] for p in container["ports"]}
                for probe, service in [("livenessProbe", "liveness"),
                                       ("readinessProbe", "fenestrad")]:
                    self.assertEqual(set(container[probe]) & {"grpc", "httpGet", "tcpSocket",
                                                              "exec"}, {"grpc"}, probe)
                    self.assertEqual(container[probe]["grpc"]["port"], ports["health"], probe)
                    self.assertEqual(container[probe]["grpc"]["service"], service, probe)
                self.assertNotEqual(ports["health"], ports["grpc"])

    def test_every_reference_resolves_to_an_object_of_the_render(self):
        for name, render in self.renders.items():
            for workload in render.workloads():
                spec = pod_spec(workload)
                volumes = {v["name"]: v for v in spec.get("volumes", [])}
                claims = {c["metadata"]["name"] for c in
                          workload["spec"].get("volumeClaimTemplates", [])}
                for volume in volumes.values():
                    with self.subTest(render=name, volume=volume["name"]):
                        if "secret" in volume:
                            self.assertIsNotNone(
                                render.get("Secret", volume["secret"]["secretName"]))
                        if "configMap" in volume:
                            self.assertIsNotNone(
                                render.get("ConfigMap", volume["configMap"]["name"]))
                for container in containers(spec):
                    with self.subTest(render=name, container=container["name"]):
                        for mount in container.get("volumeMounts", []):
                            self.assertIn(mount["name"], set(volumes) | claims)
                        for env in container.get("env", []):
                            ref = env.get("valueFrom", {}).get("secretKeyRef")
                            if ref:
                                secret = render.get("Secret", ref["name"])
                                self.assertIsNotNone(secret, ref["name"])
                                self.assertIn(ref["key"], secret.get("data", {}))
                            ref = env.get("valueFrom", {}).get("configMapKeyRef")
                            if ref:
                                self.assertIsNotNone(render.get("ConfigMap", ref["name"]))
                        for source in container.get("envFrom", []):
                            for kind, key in (("Secret", "secretRef"),
                                              ("ConfigMap", "configMapRef")):
                                if key in source:
                                    self.assertIsNotNone(render.get(kind, source[key]["name"]))
                        # $(VAR) in the command line names a variable of the container
                        names = {e["name"] for e in container.get("env", [])}
                        line = container.get("command", []) + container.get("args", [])
                        for var in re.findall(r"\$\((\w+)\)", " ".join(line)):
                            self.assertIn(var, names)

    def test_store_and_tls_come_from_the_secrets(self):
        for name, render in self.renders.items():
            with self.subTest(render=name):
                deployment, container = render.fenestrad()
                args = container["args"]
                self.assertEqual(args[args.index("--store") + 1], "$(FENESTRA_STORE)")
                env = {e["name"]: e for e in container["env"]}
                ref = env["FENESTRA_STORE"]["valueFrom"]["secretKeyRef"]
                store = decoded(render.get("Secret", ref["name"]), ref["key"])
                self.assertRegex(store, r"^postgresql://")
                # --tls-cert and --tls-key: files of the TLS Secret's volume
                volumes = {v["name"]: v for v in pod_spec(deployment)["volumes"]}
                mounts = {m["mountPath"]: m for m in container["volumeMounts"]}
                for flag, key in (("--tls-cert", "tls.crt"), ("--tls-key", "tls.key")):
                    path = args[args.index(flag) + 1]
                    folder, file = os.path.split(path)
                    self.assertEqual(file, key)
                    volume = volumes[mounts[folder]["name"]]
                    secret = render.get("Secret", volume["secret"]["secretName"])
                    self.assertEqual(secret["type"], "kubernetes.io/tls")
                    self.assertIn(key, secret["data"])
                    self.assertTrue(mounts[folder].get("readOnly"))
                # The certificate is the one make-trial-secrets.sh signed
                cert = os.path.join(self.tmp, "tls.crt")
                with open(cert, "w") as out:
                    out.write(decoded(secret, "tls.crt"))
                verified = run(["openssl", "verify", "-CAfile", self.ca, cert])
                self.assertEqual(verified.returncode, 0, verified.stdout + verified.stderr)

    def check_config(self, render, name):
        """`fenestrad --check-config` on the ConfigMap's JSON with the container's flags;
        the configuration it resolved."""
        deployment, container = render.fenestrad()
        args = list(container["args"])
        config_path = args[args.index("--config") + 1]
        folder, key = os.path.split(config_path)
        mount = [m for m in container["volumeMounts"] if m["mountPath"] == folder][0]
        volume = [v for v in pod_spec(deployment)["volumes"] if v["name"] == mount["name"]][0]
        config_map = render.get("ConfigMap", volume["configMap"]["name"])
        local = os.path.join(self.tmp, name.replace("/", "_") + ".json")
        with open(local, "w") as out:
            out.write(config_map["data"][key])
        args[args.index("--config") + 1] = local
        # fenestrad builds without the PostgreSQL store know no --store; --check-config
        # opens nothing, so the URL itself is not checked either way
        at = args.index("--store")
        if "--store" in run([FENESTRAD, "--help"]).stdout:
            env = {e["name"]: e for e in container["env"]}
            ref = env["FENESTRA_STORE"]["valueFrom"]["secretKeyRef"]
            args[at + 1] = decoded(render.get("Secret", ref["name"]), ref["key"])
        else:
            del args[at:at + 2]
        checked = run([FENESTRAD, "--check-config"] + args, cwd=self.tmp)
        self.assertEqual(checked.returncode, 0, checked.stderr)
        return json.loads(checked.stdout), config_map["data"][key]

    def test_the_configuration_is_fenestrads(self):
        with open(os.path.join(SOURCE, "deploy", "fenestrad.example.json")) as example_file:
            example = json.load(example_file)
        for name, render in self.renders.items():
            with self.subTest(render=name):
                resolved, text = self.check_config(render, name)
                # The example configuration's keys; TLS comes as flags from the Secret
                given = json.loads(text)
                self.assertLessEqual(set(example) - {"tlsCertFile", "tlsKeyFile"}, set(given))
                self.assertLessEqual(set(example["limits"]), set(given["limits"]))
                deployment, container = render.fenestrad()
                ports = {p["name"]: p["containerPort"] for p in container["ports"]}
                self.assertEqual(port_of(resolved["listenAddress"]), ports["grpc"])
                self.assertEqual(port_of(resolved["healthListen"]), ports["health"])
                self.assertEqual(resolved["auth"], "token")
                self.assertEqual(resolved["tlsCertFile"],
                                 container["args"][container["args"].index("--tls-cert") + 1])
                # The data directory: a writable volume of the pod's own, larger than the
                # daemon's limit on it
                spec = pod_spec(deployment)
                mount = [m for m in container["volumeMounts"]
                         if m["mountPath"] == resolved["dataDir"]][0]
                self.assertFalse(mount.get("readOnly", False))
                volume = [v for v in spec["volumes"] if v["name"] == mount["name"]][0]
                self.assertEqual(volume["emptyDir"]["sizeLimit"][-2:], "Gi")
                size_limit = int(volume["emptyDir"]["sizeLimit"][:-2]) << 30
                self.assertLess(int(resolved["limits"]["maxDataDirBytes"]), size_limit)
                # Running jobs get their grace, then time to reach a checkpoint
                self.assertGreater(spec["terminationGracePeriodSeconds"],
                                   resolved["shutdownGraceSeconds"])
        # A configuration fenestrad refuses makes this check fail
        broken = os.path.join(self.tmp, "broken.json")
        with open(broken, "w") as out:
            out.write('{"listenAddress": "0.0.0.0:50051", "healthListn": "0.0.0.0:8081"}')
        refused = run([FENESTRAD, "--check-config", "--config", broken])
        self.assertEqual(refused.returncode, 2)
        self.assertIn("healthListn", refused.stderr)

    def test_fenestrad_run_as_configured_answers_the_probes(self):
        """fenestrad started from the cpu overlay's ConfigMap, flags and Secrets (on loopback
        ports, SQLite in a temporary folder): the probes' services are SERVING on the
        health port, and the main port speaks TLS with the Secret's certificate."""
        import grpc

        render = self.renders["overlays/cpu"]
        deployment, container = render.fenestrad()
        args = list(container["args"])
        _, config_text = self.check_config(render, "overlays/cpu")
        config = os.path.join(self.tmp, "run_fenestrad.json")
        with open(config, "w") as out:
            out.write(config_text)
        tls = render.get("Secret", [v for v in pod_spec(deployment)["volumes"]
                                    if v["name"] == "tls"][0]["secret"]["secretName"])
        for flag, key in (("--tls-cert", "tls.crt"), ("--tls-key", "tls.key")):
            path = os.path.join(self.tmp, "run_" + key)
            with open(path, "w") as out:
                out.write(decoded(tls, key))
            args[args.index(flag) + 1] = path
        args[args.index("--config") + 1] = config
        at = args.index("--store")
        del args[at:at + 2]
        port_file = os.path.join(self.tmp, "run.port")
        daemon = subprocess.Popen(
            [FENESTRAD] + args + ["--listen", "127.0.0.1:0", "--health-listen", "127.0.0.1:0",
                                  "--data-dir", os.path.join(self.tmp, "run_data"),
                                  "--port-file", port_file],
            stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
        try:
            for _ in range(400):
                if os.path.exists(port_file) or daemon.poll() is not None:
                    break
                time.sleep(0.05)
            self.assertTrue(os.path.exists(port_file), "fenestrad did not start")
            with open(port_file) as ports:
                port, health_port = [int(line) for line in ports.read().split()]

            # grpc.health.v1.Health/Check: request field 1 = service, answer field 1 = status
            health = grpc.insecure_channel("127.0.0.1:%d" % health_port)
            check = health.unary_unary("/grpc.health.v1.Health/Check")
            for probe in ("livenessProbe", "readinessProbe"):
                service = container[probe]["grpc"]["service"].encode()
                answer = check(bytes([0x0A, len(service)]) + service, timeout=10)
                self.assertEqual(answer, b"\x08\x01", probe + ": SERVING")
            health.close()

            # The main port: TLS with the Secret's certificate, then a token is asked for
            with open(self.ca, "rb") as ca:
                credentials = grpc.ssl_channel_credentials(root_certificates=ca.read())
            main = grpc.secure_channel("localhost:%d" % port, credentials)
            with self.assertRaises(grpc.RpcError) as call:
                main.unary_unary("/fenestra.v1.JobService/List")(b"", timeout=10)
            self.assertEqual(call.exception.code(), grpc.StatusCode.UNAUTHENTICATED)
            main.close()
        finally:
            daemon.terminate()
            _, log = daemon.communicate(timeout=60)
        self.assertEqual(daemon.returncode, 0, log)

    def test_labels_and_selectors_match(self):
        for name, render in self.renders.items():
            workloads = render.workloads()
            pods = {w["metadata"]["name"]: w["spec"]["template"]["metadata"]["labels"]
                    for w in workloads}

            def selected(selector):
                return [w for w, labels in pods.items()
                        if selector.items() <= labels.items()]

            with self.subTest(render=name):
                for workload in workloads:
                    self.assertLessEqual(workload["spec"]["selector"]["matchLabels"].items(),
                                         pods[workload["metadata"]["name"]].items())
                    if workload["kind"] == "StatefulSet":
                        service = render.get("Service", workload["spec"]["serviceName"])
                        self.assertEqual(selected(service["spec"]["selector"]),
                                         [workload["metadata"]["name"]])
                # Each Service and the budget select exactly their workload's pods
                service = render.get("Service", "fenestrad")
                self.assertEqual(selected(service["spec"]["selector"]), ["fenestrad"])
                budget = render.get("PodDisruptionBudget", "fenestrad")
                self.assertEqual(selected(budget["spec"]["selector"]["matchLabels"]),
                                 ["fenestrad"])
                # Named target ports exist on the selected pods
                for service in render.all("Service"):
                    workload = [w for w in workloads if w["metadata"]["name"] in
                                selected(service["spec"]["selector"])][0]
                    names = {p["name"] for c in pod_spec(workload)["containers"]
                             for p in c.get("ports", [])}
                    for port in service["spec"]["ports"]:
                        self.assertIn(port["targetPort"], names)

    def test_security_contexts_and_resources(self):
        for name, render in self.renders.items():
            for workload in render.workloads():
                spec = pod_spec(workload)
                with self.subTest(render=name, workload=workload["metadata"]["name"]):
                    self.assertTrue(spec["securityContext"]["runAsNonRoot"])
                    # Numeric: the kubelet cannot check a user name of the image
                    self.assertGreater(spec["securityContext"]["runAsUser"], 0)
                    self.assertFalse(spec["automountServiceAccountToken"])
                for container in containers(spec):
                    with self.subTest(render=name, container=container["name"]):
                        context = container["securityContext"]
                        self.assertIs(context["allowPrivilegeEscalation"], False)
                        self.assertIs(context["readOnlyRootFilesystem"], True)
                        self.assertIs(context.get("privileged", False), False)
                        self.assertIn("ALL", context["capabilities"]["drop"])
                        for part in ("requests", "limits"):
                            self.assertLessEqual({"cpu", "memory"},
                                                 set(container["resources"][part]), part)
            # fenestrad writes only to its volumes: the data directory and /tmp
            _, container = render.fenestrad()
            writable = {m["mountPath"] for m in container["volumeMounts"]
                        if not m.get("readOnly", False)}
            self.assertEqual(writable, {"/var/lib/fenestra", "/tmp"}, name)

    def test_trial_store_is_the_trial_database(self):
        render = self.renders["overlays/trial"]
        _, container = render.fenestrad()
        ref = {e["name"]: e for e in container["env"]}["FENESTRA_STORE"]["valueFrom"]
        store = decoded(render.get("Secret", ref["secretKeyRef"]["name"]),
                        ref["secretKeyRef"]["key"])
        found = re.fullmatch(r"postgresql://(\w+):(\w+)@([\w-]+):(\d+)/(\w+)", store)
        self.assertIsNotNone(found, "store URL")
        user, password, host, port, database = found.groups()
        database_set = render.get("StatefulSet", "fenestra-postgresql")
        self.assertIsNotNone(render.get("Service", host))
        self.assertEqual(render.get("Service", host)["spec"]["ports"][0]["port"], int(port))
        postgres = pod_spec(database_set)["containers"][0]
        env = {e["name"]: e for e in postgres["env"]}
        self.assertEqual(env["POSTGRES_USER"]["value"], user)
        self.assertEqual(env["POSTGRES_DB"]["value"], database)
        ref = env["POSTGRES_PASSWORD"]["valueFrom"]["secretKeyRef"]
        self.assertEqual(decoded(render.get("Secret", ref["name"]), ref["key"]), password)
        self.assertGreaterEqual(len(password), 32)
        # fenestrad waits for it
        waits = pod_spec(render.get("Deployment", "fenestrad"))["initContainers"]
        self.assertIn(host, " ".join(waits[0]["command"]))


if __name__ == "__main__":
    parser = argparse.ArgumentParser()
    parser.add_argument("--fenestrad", required=True)
    parser.add_argument("--source", required=True)
    options, rest = parser.parse_known_args()
    FENESTRAD, SOURCE = os.path.abspath(options.fenestrad), os.path.abspath(options.source)
    unittest.main(argv=[sys.argv[0]] + rest)
