"""test_packaging.py — deploy/container/Containerfile and deploy/kubernetes/isomesh.yaml as
the programs they drive would take them (no container runtime or cluster needed):

* the image: its runtime stage installs a package for every shared library `ldd` lists for
  the built isomeshd and isomesh (mapped with dpkg -S); its entry point and the directories
  its command names exist in a tree made by deploy/install.sh --destdir, and that command,
  run from the tree, serves the viewer and the API document;
* the manifests: each Service selects the pods of a Deployment and targets a named port they
  declare; the daemon's arguments, run as written (only addresses and paths pointed at this
  machine), give a daemon that authenticates to Redis with the mounted password file (mode
  as the Secret volume sets it), joins the cluster queue and answers its probes; the
  autoscaler scales that Deployment on a metric the daemon exports; Redis with the
  ConfigMap's file is the cache deploy/redis/isomesh.conf describes and takes the password."""
import json
import os
import re
import shutil
import subprocess
import sys
import tempfile
import threading
import unittest

import yaml

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import stack  # noqa: E402
from stack import harness  # noqa: E402

CONTAINERFILE = os.path.join(stack.DEPLOY, "container", "Containerfile")
MANIFESTS = os.path.join(stack.DEPLOY, "kubernetes", "isomesh.yaml")
SKIP = stack.missing_programs()


def containerfile_stages():
    """The Containerfile's instructions per stage: [[(INSTRUCTION, text)], ...], with line
    continuations joined."""
    with open(CONTAINERFILE) as f:
        text = re.sub(r"\\\n", " ", f.read())
    stages = []
    for line in text.splitlines():
        line = line.strip()
        if not line or line.startswith("#"):
            continue
        word, _, rest = line.partition(" ")
        if word == "FROM":
            stages.append([])
        stages[-1].append((word, rest.strip()))
    return stages


def install_tree(tmp):
    dest = os.path.join(tmp, "root")
    r = subprocess.run(["sh", os.path.join(stack.DEPLOY, "install.sh"), "--build",
                        os.path.abspath(harness.BUILD), "--destdir", dest],
                       stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, timeout=300)
    if r.returncode != 0:
        raise AssertionError(r.stdout)
    return dest


def run_daemon(argv):
    """A harness.Daemon around an already made command line (its --listen port known)."""
    port = int(re.search(r"--listen[= ]\S*:(\d+)", " ".join(argv)).group(1))
    d = harness.Daemon()
    d.proc = harness.spawn_owned(argv, stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL,
                                 stderr=subprocess.PIPE, text=True, errors="replace")
    d.reader = threading.Thread(target=d._read_stderr, daemon=True)
    d.reader.start()
    d.port = port
    return d


@unittest.skipIf(SKIP, SKIP)
class ContainerfileTest(unittest.TestCase):
    def setUp(self):
        self.tmp = tempfile.mkdtemp(prefix="isomesh_image_")
        if not os.path.isdir(os.path.join(stack.ROOT, "web", "node_modules", "three", "build")):
            self.skipTest("web/node_modules/three is missing (make web-deps)")

    def tearDown(self):
        shutil.rmtree(self.tmp, ignore_errors=True)

    @unittest.skipIf(not shutil.which("dpkg"), "dpkg is missing")
    def test_the_runtime_stage_installs_every_library_the_programs_link(self):
        run = containerfile_stages()[-1]
        installs = " ".join(rest for word, rest in run if word == "RUN" and "apt-get install" in rest)
        packages = set(re.findall(r"\b((?:lib|zlib)[a-z0-9.+-]+)", installs))  # zlib1g: no lib prefix
        needed = set()
        for prog in ("isomeshd", "isomesh"):
            out = subprocess.run(["ldd", os.path.join(harness.BUILD, prog)], stdout=subprocess.PIPE,
                                 text=True, timeout=30).stdout
            for path in re.findall(r"=> (/\S+)", out):
                owner = subprocess.run(["dpkg", "-S", os.path.realpath(path)], stdout=subprocess.PIPE,
                                       stderr=subprocess.DEVNULL, text=True, timeout=30).stdout
                if not owner:
                    owner = subprocess.run(["dpkg", "-S", path], stdout=subprocess.PIPE,
                                           stderr=subprocess.DEVNULL, text=True, timeout=30).stdout
                self.assertTrue(owner, "no package owns " + path)
                needed.add(owner.split(":")[0])
        self.assertGreater(len(needed), 5)
        self.assertEqual(needed - packages - {"libc6"}, set(), "libraries the image lacks")

    def test_the_entry_point_and_command_serve_from_an_installed_tree(self):
        run = containerfile_stages()[-1]
        entry = json.loads(dict(run)["ENTRYPOINT"])
        cmd = json.loads(dict(run)["CMD"])
        copy = dict(run)["COPY"]
        self.assertEqual(copy.split()[-2:], ["/out/usr/local", "/usr/local"])
        dest = install_tree(self.tmp)
        port = stack.free_port()
        argv = [a.replace("/usr/local/", dest + "/usr/local/") for a in entry + cmd]
        argv = [a.replace("0.0.0.0:8080", "127.0.0.1:%d" % port)
                .replace("/var/cache/isomesh", os.path.join(self.tmp, "cache")) for a in argv]
        self.assertTrue(os.access(argv[0], os.X_OK), argv[0])
        d = run_daemon(argv + ["--workers", "1"])
        try:
            d.wait_ready()
            self.assertIn(b"<html", d.get("/").body.lower())
            self.assertEqual(d.get("/v1/openapi.yaml").status, 200)
            self.assertEqual(d.post("/v1/mesh", harness.sphere(0.5)).status, 200)
        finally:
            d.cleanup()


@unittest.skipIf(SKIP, SKIP)
class KubernetesTest(unittest.TestCase):
    def setUp(self):
        with open(MANIFESTS) as f:
            self.docs = [d for d in yaml.safe_load_all(f) if d]
        self.tmp = tempfile.mkdtemp(prefix="isomesh_k8s_")

    def tearDown(self):
        shutil.rmtree(self.tmp, ignore_errors=True)

    def of_kind(self, kind):
        return [d for d in self.docs if d["kind"] == kind]

    def deployment(self, name):
        return [d for d in self.of_kind("Deployment") if d["metadata"]["name"] == name][0]

    def test_services_select_deployments_and_their_named_ports(self):
        self.assertEqual(len(self.of_kind("Deployment")), 2)
        for svc in self.of_kind("Service"):
            sel = svc["spec"]["selector"]
            pods = [d for d in self.of_kind("Deployment")
                    if all(d["spec"]["template"]["metadata"]["labels"].get(k) == v
                           for k, v in sel.items())]
            self.assertEqual(len(pods), 1, svc["metadata"]["name"])
            ports = {p["name"] for c in pods[0]["spec"]["template"]["spec"]["containers"]
                     for p in c.get("ports", [])}
            for p in svc["spec"]["ports"]:
                self.assertIn(p["targetPort"], ports)
        for d in self.of_kind("Deployment"):
            self.assertEqual(d["spec"]["selector"]["matchLabels"],
                             {k: d["spec"]["template"]["metadata"]["labels"][k]
                              for k in d["spec"]["selector"]["matchLabels"]})

    def test_the_daemon_as_deployed_joins_redis_and_answers_its_probes(self):
        dep = self.deployment("isomeshd")
        pod = dep["spec"]["template"]["spec"]
        (c,) = pod["containers"]
        args = c["args"]
        # every flag is one --help documents
        help_text = subprocess.run([harness.ISOMESHD, "--help"], stdout=subprocess.PIPE,
                                   text=True, timeout=30).stdout
        for a in args:
            self.assertIn("--" + a[2:].split("=")[0] + " ", help_text, a)
        # Redis as deployed (the ConfigMap's file, the password from the secret)
        conf = self.of_kind("ConfigMap")[0]["data"]["isomesh.conf"]
        conf_path = os.path.join(self.tmp, "isomesh.conf")
        with open(conf_path, "w") as f:
            f.write(conf.replace("port 6379", "port 0").replace("bind 0.0.0.0", "bind 127.0.0.1"))
        redis_port = stack.free_port()
        secret_mode = [v["secret"]["defaultMode"] for v in pod["volumes"] if "secret" in v][0]
        secret_dir = os.path.join(self.tmp, "secret")
        os.makedirs(secret_dir)
        pw = os.path.join(secret_dir, "password")
        with open(pw, "w") as f:
            f.write("s3cret\n")
        os.chmod(pw, secret_mode)
        rproc = harness.spawn_owned([stack.REDIS_SERVER, conf_path, "--port", str(redis_port),
                                     "--dir", self.tmp, "--requirepass", "s3cret"],
                                    stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        d = None
        try:
            self.assertTrue(stack.wait_until(lambda: self.redis_ping(redis_port), 10))
            mounts = {m["name"]: m["mountPath"] for m in c["volumeMounts"]}
            http_port = stack.free_port()
            cache = os.path.join(self.tmp, "cache")
            argv = [harness.ISOMESHD] + [
                a.replace("0.0.0.0:8080", "127.0.0.1:%d" % http_port)
                 .replace("isomesh-redis:6379", "127.0.0.1:%d" % redis_port)
                 .replace(mounts["redis-secret"], secret_dir)
                 .replace(mounts["cache"], cache)
                 .replace("/usr/local/share/isomesh/web", os.path.join(stack.ROOT, "web"))
                 .replace("/usr/local/share/isomesh/proto", os.path.join(stack.ROOT, "proto"))
                for a in args]
            argv = [a for a in argv if not a.startswith("--workers")] + ["--workers=1"]
            d = run_daemon(argv)
            d.wait_ready()
            for probe in ("readinessProbe", "livenessProbe"):
                self.assertEqual(d.get(c[probe]["httpGet"]["path"]).status, 200, probe)
            self.assertTrue(stack.wait_until(lambda: d.metric("isomesh_redis_up") == 1, 10), d.log())
            self.assertEqual(d.post("/v1/mesh", harness.sphere(0.55)).status, 200)
            self.assertEqual(d.metric("isomesh_cluster_taken_total"), 1)
            # the autoscaler's target and metric
            (hpa,) = self.of_kind("HorizontalPodAutoscaler")
            self.assertEqual(hpa["spec"]["scaleTargetRef"]["name"], dep["metadata"]["name"])
            for m in hpa["spec"]["metrics"]:
                name = m[m["type"][0].lower() + m["type"][1:]]["metric"]["name"]
                self.assertIn("\n%s " % name, d.get("/metrics").body.decode())
            ann = dep["spec"]["template"]["metadata"]["annotations"]
            self.assertEqual(int(ann["prometheus.io/port"]),
                             [p["containerPort"] for p in c["ports"] if p["name"] == "http"][0])
            self.assertEqual(d.get(ann["prometheus.io/path"]).status, 200)
            # Redis is the cache deploy/redis/isomesh.conf describes
            with open(os.path.join(stack.DEPLOY, "redis", "isomesh.conf")) as f:
                shipped = self.directives(f.read())
            mine = self.directives(conf)
            for k in ("maxmemory", "maxmemory-policy", "save", "appendonly",
                      "client-output-buffer-limit"):
                self.assertEqual(mine[k], shipped[k], k)
        finally:
            if d:
                d.cleanup()
            stack.stop_process(rproc)

    @staticmethod
    def directives(text):
        out = {}
        for line in text.splitlines():
            line = line.strip()
            if line and not line.startswith("#"):
                k, _, v = line.partition(" ")
                out[k] = v
        return out

    @staticmethod
    def redis_ping(port):
        """Redis answers (NOAUTH counts: it asks for the password)."""
        try:
            stack.redis_command(port, "PING", timeout=1)
        except stack.RedisError as e:
            return "NOAUTH" in str(e)
        except OSError:
            return False
        return True


if __name__ == "__main__":
    unittest.main()
