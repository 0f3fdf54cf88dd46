"""test_cluster.py — several isomesh daemons acting as one service, as deploy/README.md sets it
up, on loopback: redis-server (deploy/redis/isomesh.conf), two daemons sharing it (--redis),
nginx in front (deploy/nginx/isomesh.conf pointed at both). Every process is started and
stopped by the tests.

A mesh computed through nginx is a shared hit on the other daemon, bytes identical; another
format of a key known only to the other daemon is computed from the canonical request in
Redis; identical concurrent requests to both daemons compute once; nginx keeps the daemons'
immutable caching headers, answers 304, gzips JSON/YAML/JS but not Draco or glb, refuses
bodies over the limit, limits request rates per client address and per token (across
addresses), streams job events unbuffered and keeps a job's routes on its daemon; a damaged entry in Redis is dropped and recomputed."""
import http.client
import json
import os
import sys
import threading
import unittest

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import stack  # noqa: E402
from stack import harness  # noqa: E402

SKIP = stack.missing_programs()


def sphere(r):
    return harness.sphere(r)


HELD_DEADLINE = "600s"


def held(tag):
    """A small mesh distinct per tag, for the tests that pause the workers (Stack.pause_workers)
    to hold a computation running while they observe it: its duration does not matter."""
    return sphere(0.69 + tag / 1000)


def joined(t, box, timeout=120):
    t.join(timeout)
    if t.is_alive():
        raise AssertionError("a background request did not finish")
    if "error" in box:
        raise box["error"]
    return box["result"]


def started(d):
    return d.metric("isomesh_computations_started_total")


@unittest.skipIf(SKIP, SKIP)
class ClusterTest(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        # a job deadline no paused computation (see held) reaches on a loaded machine
        cls.s = stack.Stack(n=2, daemon_args=("--job-timeout", HELD_DEADLINE)).start()
        cls.a, cls.b = cls.s.daemons
        cls.ng = cls.s.nginx

    @classmethod
    def tearDownClass(cls):
        reports = cls.s.cleanup()
        if reports:
            raise AssertionError("sanitizer reports:\n" + "\n".join(reports))

    def wait_stored(self, key):
        self.assertTrue(stack.wait_stored(self.s.redis, key), "never stored in Redis")

    def computed_by(self, before):
        """The daemons whose started-computations count grew since before (a list)."""
        return [d for d, n in zip(self.s.daemons, before) if started(d) > n]

    def test_a_mesh_computed_through_nginx_is_a_hit_on_the_other_daemon(self):
        req = sphere(0.61)
        before = [started(d) for d in self.s.daemons]
        first = self.ng.post("/v1/mesh", req)
        self.assertEqual(first.status, 200, first.body[:300])
        self.assertEqual(first.header("X-Cache"), "miss")
        who = self.computed_by(before)
        self.assertEqual(len(who), 1, "exactly one daemon computed it")
        other = self.b if who[0] is self.a else self.a
        self.wait_stored(first.header("ETag").strip('"'))
        n_other = started(other)
        hits = other.metric("isomesh_cache_tier_hits_total", tier="redis")
        second = other.post("/v1/mesh", req)
        self.assertEqual(second.status, 200)
        self.assertEqual(second.header("X-Cache"), "shared")
        self.assertEqual(second.body, first.body)
        self.assertEqual(second.header("ETag"), first.header("ETag"))
        self.assertEqual(started(other), n_other, "the other daemon computed nothing")
        self.assertEqual(other.metric("isomesh_cache_tier_hits_total", tier="redis"), hits + 1)
        # now in the other daemon's own memory
        third = other.post("/v1/mesh", req)
        self.assertEqual(third.header("X-Cache"), "hit")
        v, f = harness.draco_counts(third.body)
        self.assertGreater(f, 0)
        # stats came along
        key = first.header("ETag").strip('"')
        st = other.get("/v1/meshes/%s/stats" % key)
        self.assertEqual(st.status, 200)
        self.assertEqual(st.json()["key"], key)

    def test_another_format_of_a_key_known_elsewhere_is_computed_from_redis(self):
        req = sphere(0.62)
        first = self.a.post("/v1/mesh", req)
        self.assertEqual(first.status, 200)
        key = first.header("ETag").strip('"')
        self.wait_stored(key)
        # b never saw this request: it finds the canonical request in Redis
        n_b = started(self.b)
        glb = self.b.get("/v1/meshes/%s.glb" % key)
        self.assertEqual(glb.status, 200, glb.body[:300])
        self.assertEqual(glb.body[:4], b"glTF")
        self.assertEqual(started(self.b), n_b + 1)
        self.assertEqual(glb.header("Cache-Control"), "public, max-age=31536000, immutable")
        # and a reaches the glb through Redis without computing it
        n_a = started(self.a)
        again = self.a.get("/v1/meshes/%s.glb" % key)
        self.assertEqual(again.status, 200)
        self.assertEqual(again.body, glb.body)
        self.assertEqual(started(self.a), n_a)
        # a key nobody knows stays unknown everywhere
        unknown = self.b.get("/v1/meshes/%s.drc" % ("0123456789abcdef" * 4))
        self.assertEqual(unknown.status, 404)
        self.assertEqual(unknown.json()["error"]["code"], "unknown_mesh")

    def test_identical_concurrent_requests_on_both_daemons_compute_once(self):
        req = held(1)
        before = sum(started(d) for d in self.s.daemons)
        waits = sum(d.metric("isomesh_redis_lock_waits_total") for d in self.s.daemons)
        suspended = [d.metric("isomesh_suspended_connections") for d in self.s.daemons]
        self.s.pause_workers()  # the first computation runs until all four requests wait
        try:
            jobs = [harness.in_background(lambda: self.a.post("/v1/mesh", req))]
            self.assertTrue(stack.wait_until(
                lambda: sum(d.metric("isomesh_workers_busy") for d in self.s.daemons) == 1, 30))
            jobs += [harness.in_background(lambda d=d: d.post("/v1/mesh", req))
                     for d in (self.b, self.a, self.b)]
            self.assertTrue(stack.wait_until(lambda: [
                d.metric("isomesh_suspended_connections") - n
                for d, n in zip(self.s.daemons, suspended)] == [2, 2], 30))
        finally:
            self.s.resume_workers()
        answers = [joined(*j) for j in jobs]
        for r in answers:
            self.assertEqual(r.status, 200, r.body[:300])
            self.assertEqual(r.body, answers[0].body)
        self.assertEqual(sum(started(d) for d in self.s.daemons), before + 1)
        self.assertGreaterEqual(
            sum(d.metric("isomesh_redis_lock_waits_total") for d in self.s.daemons), waits + 1)
        self.assertEqual(sorted(r.header("X-Cache") for r in answers).count("shared"), 2)

    def test_a_mixed_load_computes_each_distinct_mesh_once_in_the_whole_service(self):
        distinct = [sphere(0.3 + i / 50) for i in range(12)]
        work = [(i, target) for i in range(len(distinct)) for target in ("a", "b", "ng", "a")]
        work = work[1::2] + work[0::2]  # spread copies apart
        before = sum(started(d) for d in self.s.daemons)
        targets = {"a": self.a, "b": self.b, "ng": self.ng}
        results, lock = {}, threading.Lock()

        def worker(items):
            for i, t in items:
                r = targets[t].post("/v1/mesh", distinct[i])
                with lock:
                    results.setdefault(i, []).append(r)
        threads = [threading.Thread(target=worker, args=(work[k::8],), daemon=True)
                   for k in range(8)]
        for t in threads:
            t.start()
        for t in threads:
            t.join(120)
        self.assertEqual(sum(len(v) for v in results.values()), len(work))
        for i, answers in results.items():
            for r in answers:
                self.assertEqual(r.status, 200, r.body[:300])
                self.assertEqual(r.body, answers[0].body)
        self.assertEqual(sum(started(d) for d in self.s.daemons), before + len(distinct))

    def test_nginx_keeps_the_immutable_caching_headers_and_answers_304(self):
        first = self.ng.post("/v1/mesh", sphere(0.63))
        self.assertEqual(first.status, 200)
        self.assertEqual(first.header("Cache-Control"), "no-store")
        location = first.header("Location")
        r = self.ng.get(location, headers={"Accept-Encoding": "gzip"})
        self.assertEqual(r.status, 200)
        self.assertEqual(r.header("Cache-Control"), "public, max-age=31536000, immutable")
        self.assertEqual(r.header("ETag"), first.header("ETag"))
        self.assertIsNone(r.header("Content-Encoding"), "Draco is not gzipped")
        self.assertEqual(r.body, first.body)
        again = self.ng.get(location, headers={"If-None-Match": r.header("ETag")})
        self.assertEqual(again.status, 304)
        self.assertEqual(again.body, b"")
        glb = self.ng.get(location.replace(".drc", ".glb"), headers={"Accept-Encoding": "gzip"})
        self.assertEqual(glb.status, 200)
        self.assertIsNone(glb.header("Content-Encoding"), "glb is not gzipped")
        self.assertEqual(glb.body[:4], b"glTF")

    def test_nginx_keeps_meshes_served_by_key_and_never_rate_limits_reading_them(self):
        first = self.ng.post("/v1/mesh", sphere(0.66))
        self.assertEqual(first.status, 200)
        location = first.header("Location")
        route = "/v1/meshes/{key}.{format}"

        def served_by_daemons():
            return sum(d.metric("isomesh_http_requests_total", route=route, status="200")
                       for d in self.s.daemons)
        r = self.ng.get(location)
        self.assertEqual((r.status, r.header("X-Cache-Status")), (200, "MISS"))
        self.assertEqual(r.body, first.body)
        before = served_by_daemons()
        # far past any rate limit's burst, from one address: every answer nginx's own copy
        conn = http.client.HTTPConnection("127.0.0.1", self.ng.port, timeout=30,
                                          source_address=("127.0.0.12", 0))
        try:
            for _ in range(400):
                conn.request("GET", location)
                resp = conn.getresponse()
                body = resp.read()
                self.assertEqual((resp.status, resp.getheader("X-Cache-Status")), (200, "HIT"))
                self.assertEqual(body, first.body)
        finally:
            conn.close()
        self.assertEqual(served_by_daemons(), before)
        # a request with a token (--private) always reaches a daemon, and is never kept
        bearer = {"Authorization": "Bearer ism_" + "A" * 43}
        other = self.ng.get(location.replace(".drc", ".ply"), headers=bearer)
        self.assertEqual((other.status, other.header("X-Cache-Status")), (200, "BYPASS"))
        self.assertEqual(self.ng.get(location.replace(".drc", ".ply")).header("X-Cache-Status"),
                         "MISS")
        # errors are not kept either
        missing = "/v1/meshes/%s.drc" % ("0" * 64)
        self.assertEqual(self.ng.get(missing).status, 404)
        self.assertNotEqual(self.ng.get(missing).header("X-Cache-Status"), "HIT")

    def test_nginx_gzips_text_only(self):
        gz = {"Accept-Encoding": "gzip"}
        for path, ctype in (("/v1/presets", "application/json"),
                            ("/v1/openapi.yaml", "application/yaml"),
                            ("/js/api.js", "text/javascript"),
                            ("/", "text/html")):
            r = self.ng.get(path, headers=gz)
            self.assertEqual(r.status, 200, path)
            self.assertTrue(r.header("Content-Type").startswith(ctype), (path, r.header("Content-Type")))
            self.assertEqual(r.header("Content-Encoding"), "gzip", path)
            plain = self.ng.get(path)
            self.assertIsNone(plain.header("Content-Encoding"))
            self.assertEqual(stack.gunzip(r.body), plain.body, path)
        json.loads(stack.gunzip(self.ng.get("/v1/presets", headers=gz).body))

    def test_bodies_over_the_limit_are_refused_by_nginx(self):
        big = b'{"expr": "' + b"x" * (300 * 1024) + b'"}'
        r = self.ng.post("/v1/mesh", big, headers={"Content-Type": "application/json"})
        self.assertEqual(r.status, 413)
        ok = self.ng.post("/v1/mesh", sphere(0.64))
        self.assertEqual(ok.status, 200)

    def test_rate_limit_per_client_address(self):
        req = sphere(0.65)
        self.assertEqual(self.ng.post("/v1/mesh", req).status, 200)  # cached from now on
        statuses = [self.ng.post("/v1/mesh", req, source="127.0.0.7").status for _ in range(40)]
        self.assertIn(429, statuses)
        self.assertEqual(statuses[0], 200)
        self.assertTrue(set(statuses) <= {200, 429}, statuses)
        # another client is not affected
        self.assertEqual(self.ng.post("/v1/mesh", req, source="127.0.0.8").status, 200)

    def test_rate_limit_per_token_across_addresses(self):
        req = sphere(0.66)
        self.assertEqual(self.ng.post("/v1/mesh", req).status, 200)  # cached from now on
        sources = ["127.0.0.%d" % i for i in range(11, 15)]  # 10 each: under the address burst
        token = {"Authorization": "Bearer ism_rate_limit_test_token"}
        statuses = [self.ng.post("/v1/mesh", req, headers=token, source=sources[i % 4]).status
                    for i in range(40)]
        self.assertEqual(statuses[0], 200)
        self.assertIn(429, statuses)  # the token's 21-request burst spent over four addresses
        self.assertTrue(set(statuses) <= {200, 429}, statuses)
        # four other addresses without a token, ten requests each: their own limits only
        others = ["127.0.0.%d" % i for i in range(21, 25)]
        statuses = [self.ng.post("/v1/mesh", req, source=others[i % 4]).status
                    for i in range(40)]
        self.assertEqual(set(statuses), {200}, statuses)

    def test_job_events_pass_through_nginx_unbuffered_and_jobs_stay_on_their_daemon(self):
        self.s.pause_workers()  # the job runs until its first event came through
        conn = http.client.HTTPConnection("127.0.0.1", self.ng.port, timeout=120,
                                          source_address=("127.0.0.9", 0))
        try:
            r = self.ng.post("/v1/jobs", held(2), source="127.0.0.9")
            self.assertEqual(r.status, 202, r.body[:300])
            job = r.json()
            for _ in range(10):  # every route of the job reaches the daemon holding it
                st = self.ng.get(job["url"], source="127.0.0.9")
                self.assertEqual(st.status, 200, st.body[:200])
            conn.request("GET", job["events_url"], headers={"Accept-Encoding": "gzip"})
            resp = conn.getresponse()
            self.assertEqual(resp.status, 200)
            self.assertEqual(resp.getheader("Content-Type"), "text/event-stream")
            self.assertIsNone(resp.getheader("Content-Encoding"))
            first = b""
            while b"\n\n" not in first:
                chunk = resp.read1(4096)
                self.assertTrue(chunk, "the stream ended before its first event")
                first += chunk
            # The first event came through while the job still ran: nothing held it back.
            state = self.ng.get(job["url"], source="127.0.0.9").json()["state"]
            self.assertIn(state, ("queued", "running"))
            self.s.resume_workers()
            rest = resp.read()
        finally:
            self.s.resume_workers()
            conn.close()
        text = (first + rest).decode()
        events = [dict(line.split(": ", 1) for line in block.splitlines())
                  for block in text.strip().split("\n\n")]
        self.assertEqual(events[0]["event"], "progress")
        self.assertEqual(events[-1]["event"], "done")
        mesh = self.ng.get(json.loads(events[-1]["data"])["mesh_url"])
        self.assertEqual(mesh.status, 200)

    def test_open_requests_are_limited_per_client_address(self):
        src = "127.0.0.10"
        self.s.pause_workers()  # the job runs (its streams stay open) until every answer is in
        try:
            self._open_requests_are_limited(src)
        finally:
            self.s.resume_workers()

    def _open_requests_are_limited(self, src):
        job = self.ng.post("/v1/jobs", held(4), source=src).json()
        statuses, lock = [], threading.Lock()
        opened = threading.Barrier(41, timeout=60)

        def stream():
            conn = http.client.HTTPConnection("127.0.0.1", self.ng.port, timeout=120,
                                              source_address=(src, 0))
            try:
                conn.request("GET", job["events_url"])
                resp = conn.getresponse()
                with lock:
                    statuses.append(resp.status)
                opened.wait()  # every answer is in while the streams are still open
                resp.read()
            finally:
                conn.close()
        threads = [threading.Thread(target=stream, daemon=True) for _ in range(40)]
        for t in threads:
            t.start()
        opened.wait()
        self.s.resume_workers()  # the job ends: so do its streams
        for t in threads:
            t.join(120)
        self.assertEqual(len(statuses), 40)
        self.assertEqual(statuses.count(200), 32, "limit_conn isomesh_conn 32")
        self.assertEqual(statuses.count(429), 8)
        # another address is not affected meanwhile
        self.assertEqual(self.ng.get("/v1/presets", source="127.0.0.11").status, 200)

    def test_an_incomplete_result_in_redis_is_recomputed(self):
        """A daemon that dies while writing a result leaves part of it: never served."""
        req = sphere(0.67)
        first = self.a.post("/v1/mesh", req)
        self.assertEqual(first.status, 200)
        key = first.header("ETag").strip('"')
        stats = "isomesh:v1:%s.stats.json" % key
        self.assertTrue(stack.wait_until(lambda: self.s.redis.command("EXISTS", stats) == 1, 10))
        self.assertEqual(self.s.redis.command("DEL", stats), 1)
        n_b = started(self.b)
        second = self.b.post("/v1/mesh", req)
        self.assertEqual(second.status, 200)
        self.assertEqual(second.header("X-Cache"), "miss")
        self.assertEqual(started(self.b), n_b + 1)
        st = self.b.get("/v1/meshes/%s/stats" % key)
        self.assertEqual(st.status, 200)
        self.assertTrue(stack.wait_until(lambda: self.s.redis.command("EXISTS", stats) == 1, 10))

    def test_a_damaged_entry_in_redis_is_dropped_and_recomputed(self):
        req = sphere(0.66)
        first = self.a.post("/v1/mesh", req)
        self.assertEqual(first.status, 200)
        key = first.header("ETag").strip('"')
        name = "isomesh:v1:%s.drc" % key
        value = stack.wait_until(lambda: self.s.redis.command("GET", name), 10)  # written after
        self.assertIsNotNone(value)
        damaged = bytearray(value)
        damaged[len(damaged) // 2] ^= 0x20
        self.assertEqual(self.s.redis.command("SET", name, bytes(damaged)), "OK")
        corrupt = self.b.metric("isomesh_cache_corrupt_total", tier="redis")
        n_b = started(self.b)
        second = self.b.post("/v1/mesh", req)
        self.assertEqual(second.status, 200)
        self.assertEqual(second.body, first.body, "recomputed, not served damaged")
        self.assertEqual(started(self.b), n_b + 1)
        self.assertEqual(self.b.metric("isomesh_cache_corrupt_total", tier="redis"), corrupt + 1)
        self.assertTrue(stack.wait_until(
            lambda: self.s.redis.command("GET", name) == value, 10),
            "the recomputed entry replaced the damaged one")


if __name__ == "__main__":
    unittest.main()
