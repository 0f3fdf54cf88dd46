"""test_fairness.py — sharing one isomeshd, with one worker so the order of service is plain:
one user floods 50 jobs and a second user's single job still starts before the flood's third
(round robin across users — by token user, and by client address without tokens — while the
fifo order, the reference, makes it wait for the whole flood); a user over the per-user limit
(--user-jobs, or jobs=N in the tokens file) gets 429 with Retry-After while another user is
still accepted; running=N holds a user's extra jobs back while another user's job takes the
free worker; two users asking for the same mesh compute it once; cache hits are answered
during a flood without queueing; /metrics shows each user's queued and running jobs, ten
users by name at most and the rest summed as "other".

Every check is an order or a count read from the daemon (job start times from GET /v1/jobs,
metrics), never a duration. The flood starts behind a slow "blocker" job of the flooding user
that is canceled once everything is queued, so the order does not depend on machine speed."""
import http.client
import json
import os
import subprocess
import sys
import tempfile
import unittest

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from harness import ISOMESHD, SLOW, Daemon, Response, sphere, wait_until  # noqa: E402

FLOOD = 50


def flood_request(i):
    """A distinct request per i, each a small fraction of a second of work (depth 5: the order
    of service is what these tests read, not the mesh; depth 7 made the suite 3x costlier)."""
    return {"preset": "gyroid-ball", "params": {"k": 4 + i / 1000}, "depth": {"max": 5},
            "max_error": None}


def add_token(path, name, *opts):
    r = subprocess.run([ISOMESHD, "token", "add", name, "--file", path] + list(opts),
                       stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, timeout=30)
    if r.returncode != 0:
        raise AssertionError(r.stderr)
    return {"Authorization": "Bearer " + r.stdout.strip()}


def request_from(d, source, method, path, body=None, headers=None):
    """A request from another loopback address (another client when tokens are off)."""
    conn = http.client.HTTPConnection("127.0.0.1", d.port, timeout=60, source_address=(source, 0))
    try:
        hdrs = dict(headers or {})
        if body is not None:
            body = json.dumps(body).encode()
            hdrs["Content-Type"] = "application/json"
        conn.request(method, path, body=body, headers=hdrs)
        r = conn.getresponse()
        return Response(r.status, r.getheaders(), r.read())
    finally:
        conn.close()


class Client:
    """One user: a token's headers, or a loopback source address."""

    def __init__(self, d, headers=None, source=None):
        self.d, self.headers, self.source = d, headers or {}, source

    def call(self, method, path, body=None):
        if self.source:
            return request_from(self.d, self.source, method, path, body, self.headers)
        return self.d.request(method, path, body=body, headers=self.headers)

    def submit(self, body):
        r = self.call("POST", "/v1/jobs", body)
        if r.status != 202:
            raise AssertionError("job refused: %d %s" % (r.status, r.body[:200]))
        return r.json()

    def job(self, job):
        return self.call("GET", job["url"]).json()

    def cancel(self, job):
        return self.call("DELETE", job["url"])

    def wait_done(self, job):
        return wait_until("job " + job["id"], lambda: (lambda j: j if j["state"] not in
                                                        ("queued", "running") else None)(self.job(job)))

    def jobs(self):
        return {j["id"]: j for j in self.call("GET", "/v1/jobs").json()["jobs"]}


class FairnessTest(unittest.TestCase):
    def setUp(self):
        self.tmp = tempfile.TemporaryDirectory()
        self.tokens = os.path.join(self.tmp.name, "tokens")

    def tearDown(self):
        self.tmp.cleanup()

    def flood_then_one(self, d, flooder, other, n):
        """The flooder's blocker runs; n - 1 more of its jobs queue; then the other user's
        single job; the blocker is canceled. Returns (flood jobs incl. the blocker, the other's
        job finished, the flooder's jobs as listed by GET /v1/jobs at that point)."""
        blocker = flooder.submit(SLOW)
        wait_until("the blocker running", lambda: flooder.job(blocker)["state"] == "running")
        flood = [blocker] + [flooder.submit(flood_request(i)) for i in range(1, n)]
        single = other.submit(flood_request(1000))
        self.assertEqual(self.d_metric(d, "isomesh_queue_depth"), n)
        self.assertEqual(flooder.cancel(blocker).json()["state"], "canceled")
        done = other.wait_done(single)
        self.assertEqual(done["state"], "done", done)
        return flood, done, flooder.jobs()

    @staticmethod
    def d_metric(d, name, **labels):
        return d.metric(name, **labels)

    def assert_started_before_third(self, flood, single, listed):
        third = listed[flood[2]["id"]]
        self.assertIn("started", single)
        if "started" in third:  # ISO 8601 with milliseconds: the text order is the time order
            self.assertLess(single["started"], third["started"])
        self.assertGreaterEqual(single["queue_ms"], 0)
        # and the flood's later jobs are still waiting: the single job did not wait for them
        waiting = [j for j in flood[3:] if listed[j["id"]]["state"] == "queued"]
        self.assertGreater(len(waiting), FLOOD // 2)

    def test_a_second_user_starts_before_the_floods_third_job(self):
        alice = add_token(self.tokens, "alice")
        bob = add_token(self.tokens, "bob")
        with Daemon("--workers", "1", "--queue", "100", "--user-jobs", "100",
                    "--tokens", self.tokens) as d:
            a, b = Client(d, alice), Client(d, bob)
            flood, single, listed = self.flood_then_one(d, a, b, FLOOD)
            self.assert_started_before_third(flood, single, listed)
            self.assertEqual(single["user"], "bob")
            m = d.metrics()
            self.assertGreater(m['isomesh_user_jobs{state="queued",user="alice"}'], FLOOD // 2)
            self.assertNotIn('isomesh_user_jobs{state="queued",user="bob"}', m)  # bob is done
            self.assertEqual(m["isomesh_users_active"], 1)

    def test_without_tokens_the_client_address_is_the_user(self):
        with Daemon("--workers", "1", "--queue", "100", "--user-jobs", "100") as d:
            a, b = Client(d), Client(d, source="127.0.0.2")
            flood, single, listed = self.flood_then_one(d, a, b, FLOOD)
            self.assert_started_before_third(flood, single, listed)
            self.assertEqual(single["user"], "127.0.0.2")
            self.assertGreater(d.metric("isomesh_user_jobs", user="127.0.0.1", state="queued"),
                               FLOOD // 2)

    def test_the_fifo_reference_makes_the_second_user_wait_for_the_flood(self):
        # The same scenario served oldest first: the single job starts after every flood job,
        # so the fair test above would fail on a FIFO queue.
        n = 5
        with Daemon("--workers", "1", "--queue-order", "fifo") as d:
            a, b = Client(d), Client(d, source="127.0.0.2")
            flood, single, listed = self.flood_then_one(d, a, b, n)
            for j in flood[1:]:
                self.assertEqual(listed[j["id"]]["state"], "done")
                self.assertLess(listed[j["id"]]["started"], single["started"])

    def test_per_user_limit_is_429_while_another_user_is_served(self):
        alice = add_token(self.tokens, "alice", "--jobs", "2")  # her own limit
        bob = add_token(self.tokens, "bob")                     # the default, --user-jobs 3
        with Daemon("--workers", "1", "--queue", "20", "--user-jobs", "3",
                    "--tokens", self.tokens) as d:
            a, b = Client(d, alice), Client(d, bob)
            blocker = a.submit(SLOW)
            wait_until("the blocker running", lambda: a.job(blocker)["state"] == "running")
            second = a.submit(flood_request(1))
            for r in (a.call("POST", "/v1/jobs", flood_request(2)),
                      a.call("POST", "/v1/mesh", flood_request(3))):
                self.assertEqual(r.status, 429, r.body[:200])
                self.assertEqual(r.json()["error"]["code"], "too_many_requests")
                self.assertGreater(int(r.header("Retry-After")), 0)
            bobs = [b.submit(flood_request(10 + i)) for i in range(3)]
            over = b.call("POST", "/v1/jobs", flood_request(20))
            self.assertEqual(over.status, 429)
            # a request for a computation already in flight joins it: not a new one
            self.assertEqual(a.call("POST", "/v1/jobs", flood_request(10)).status, 202)
            self.assertEqual(d.metric("isomesh_rejected_total", reason="client_limit"), 3)
            self.assertEqual(d.metric("isomesh_user_jobs", user="alice", state="running"), 1)
            self.assertEqual(d.metric("isomesh_user_jobs", user="alice", state="queued"), 1)
            self.assertEqual(d.metric("isomesh_user_jobs", user="bob", state="queued"), 3)
            # once one of hers ends (the pool stops the canceled computation), alice may submit
            a.cancel(blocker)
            self.assertTrue(d.wait_metric("isomesh_worker_restarts_total", 1, reason="cancel"))
            self.assertEqual(a.call("POST", "/v1/jobs", flood_request(2)).status, 202)
            for j in bobs + [second]:
                self.assertIn(a.wait_done(j)["state"], ("done",))

    def test_running_limit_holds_a_users_extra_jobs_while_another_user_computes(self):
        alice = add_token(self.tokens, "alice", "--running", "1")
        bob = add_token(self.tokens, "bob")
        with Daemon("--workers", "2", "--tokens", self.tokens) as d:
            a, b = Client(d, alice), Client(d, bob)
            first = a.submit(SLOW)
            wait_until("alice's first job running", lambda: a.job(first)["state"] == "running")
            second = a.submit(dict(SLOW, params={"k": 4.5}))
            theirs = b.submit(sphere(0.7))
            self.assertEqual(b.wait_done(theirs)["state"], "done")
            # a worker was free all along, but alice may run one at a time
            self.assertEqual(a.job(first)["state"], "running")
            self.assertEqual(a.job(second)["state"], "queued")
            self.assertEqual(d.metric("isomesh_user_jobs", user="alice", state="queued"), 1)
            for j in (second, first):
                a.cancel(j)

    def test_two_users_asking_for_the_same_mesh_compute_it_once(self):
        alice = add_token(self.tokens, "alice")
        bob = add_token(self.tokens, "bob")
        with Daemon("--workers", "1", "--tokens", self.tokens) as d:
            a, b = Client(d, alice), Client(d, bob)
            blocker = a.submit(SLOW)
            # running before it is canceled (a worker not yet ready would leave it queued, and
            # a canceled queued job starts no computation)
            wait_until("the blocker running", lambda: a.job(blocker)["state"] == "running")
            mine = a.submit(flood_request(7))
            # bob asks for the same mesh, written differently (key order, a default spelled out)
            same = {"depth": {"max": 5, "min": 3}, "params": {"k": 4.007}, "preset": "gyroid-ball",
                    "max_error": None}
            theirs = b.submit(same)
            self.assertEqual(theirs["key"], mine["key"])
            self.assertEqual(d.metric("isomesh_singleflight_joins_total"), 1)
            a.cancel(blocker)
            done_a, done_b = a.wait_done(mine), b.wait_done(theirs)
            self.assertEqual((done_a["state"], done_b["state"]), ("done", "done"))
            self.assertEqual(done_a["started"], done_b["started"])
            self.assertEqual(d.metric("isomesh_computations_started_total"), 2)  # blocker + one
            self.assertEqual(d.metric("isomesh_computations_total", outcome="ok"), 1)

    def test_user_labels_in_metrics_are_capped_with_the_rest_as_other(self):
        with Daemon("--workers", "1") as d:
            a = Client(d)
            blocker = a.submit(SLOW)
            wait_until("the blocker running", lambda: a.job(blocker)["state"] == "running")
            others = [Client(d, source="127.0.0.%d" % (i + 2)) for i in range(12)]
            jobs = [(c, c.submit(flood_request(i))) for i, c in enumerate(others)]
            m = d.metrics()
            users = {k.split('user="')[1].split('"')[0] for k in m if k.startswith("isomesh_user_jobs{")}
            self.assertEqual(len(users), 11, users)  # the top 10, and "other"
            self.assertIn("other", users)
            self.assertIn("127.0.0.1", users)  # the heaviest: one running
            queued = sum(v for k, v in m.items() if k.startswith("isomesh_user_jobs{") and 'state="queued"' in k)
            running = sum(v for k, v in m.items() if k.startswith("isomesh_user_jobs{") and 'state="running"' in k)
            self.assertEqual((queued, running), (12, 1))
            self.assertEqual(m['isomesh_user_jobs{state="queued",user="other"}'], 3)
            self.assertEqual(m["isomesh_users_active"], 13)
            a.cancel(blocker)
            for c, j in jobs:
                c.cancel(j)

    def test_cache_hits_are_served_during_a_flood_without_queueing(self):
        with Daemon("--workers", "1", "--queue", "100", "--user-jobs", "100") as d:
            a, b = Client(d), Client(d, source="127.0.0.2")
            warm = b.call("POST", "/v1/mesh", sphere(0.5))
            self.assertEqual(warm.status, 200)
            key = warm.header("ETag")[1:-1]
            blocker = a.submit(SLOW)
            wait_until("the blocker running", lambda: a.job(blocker)["state"] == "running")
            flood = [a.submit(flood_request(i)) for i in range(1, 31)]
            started = d.metric("isomesh_computations_started_total")
            for _ in range(10):
                hit = b.call("POST", "/v1/mesh", sphere(0.5))
                self.assertEqual(hit.status, 200)
                self.assertEqual(hit.header("X-Cache"), "hit")
                timing = hit.header("Server-Timing")
                self.assertIn('cache;desc="hit"', timing)
                self.assertNotIn("queue;", timing)
                self.assertEqual(hit.body, warm.body)
            self.assertEqual(b.call("GET", "/v1/meshes/%s.drc" % key).status, 200)
            job = b.submit(sphere(0.5))
            self.assertEqual(job["state"], "done")
            self.assertNotIn("started", job)  # never waited for or ran on a worker
            # all of that while the flood still waited behind the blocker
            self.assertEqual(a.job(blocker)["state"], "running")
            self.assertEqual(d.metric("isomesh_queue_depth"), 30)
            self.assertEqual(d.metric("isomesh_computations_started_total"), started)
            a.cancel(blocker)
            for j in flood:
                a.cancel(j)


if __name__ == "__main__":
    unittest.main()
