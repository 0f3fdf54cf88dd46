"""test_lockout.py — a daemon that a few users cannot lock (issue 17), each red-team case on a
real isomeshd: one user's flood of job posts evicts only that user's own finished job records
(another user's record stays readable); long computations of several users do not keep a
small request of another user from a worker; a user alone uses every worker, and keeps half
of them while another user waits (the default --user-running); a request's deadline counts its time on a worker,
and its wait for one has its own bound (--queue-timeout) answered with a clear 503; a
hopeless expression (sin(1e300*x) + 3*y) is refused with 422 and never holds a worker.

Bounded everywhere: the long computations are stopped by the daemon's shutdown, every wait has
a deadline, and no assertion depends on how fast this machine computes except the generous
bound on the small request (a sphere at depth 5 takes milliseconds; the bound is seconds)."""
import json
import os
import socket
import sys
import time
import unittest

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from reltools import (Daemon, busy_work, http_request, metric_key, sanitizer_build,  # noqa: E402
                      sphere, wait_until)
from harness import ISOMESHD  # noqa: E402

USER_JOBS_KEPT = 1000  # jobs.c: records one user keeps
# Issue 17's flood at its own scale: past the 10,000 records of the whole table (jobs.c), so
# a table that evicted the oldest record of anyone when full would drop the other user's (a
# flood of 1,100 never fills the table and could not tell). Sent pipelined, PIPELINE posts at
# a time on one connection: measured 6.5 s for all 10,100 at load 29 on 2 cores (1,100 took
# 2.1 s).
FLOOD_POSTS = 10100
PIPELINE = 100
# The small request beside long ones: the bound (about 1 s measured here: a
# worker respawn and milliseconds of work), or under AddressSanitizer, whose workers start
# and compute several times slower, a looser one; without the fix it waits out the long
# requests' 60 s deadline either way.
SMALL_BOUND_S = 30.0 if sanitizer_build(ISOMESHD) else 5.0


def hopeless(k):
    """Cheap to send, never resolvable: the zero set oscillates far below any cell size (the
    octree would refine everywhere up to the deadline). Refused at once (422 unresolvable)."""
    return {"expr": "sin(1e300*x) + %g*y" % k}


def post_from(port, source, path, body, timeout=60):
    return http_request(port, "POST", path, body, timeout=timeout, source=source)


def pipelined_posts(port, path, body, n, timeout=120):
    """(status, body) of n POSTs of body sent PIPELINE at a time on one connection from
    127.0.0.1, each answer framed by its Content-Length."""
    data = json.dumps(body).encode()
    req = (b"POST %s HTTP/1.1\r\nHost: x\r\nContent-Type: application/json\r\n"
           b"Content-Length: %d\r\n\r\n" % (path.encode(), len(data))) + data
    answers = []
    with socket.create_connection(("127.0.0.1", port), timeout=timeout) as s:
        f = s.makefile("rb")
        while len(answers) < n:
            k = min(PIPELINE, n - len(answers))
            s.sendall(req * k)
            for _ in range(k):
                status = int(f.readline().split()[1])
                length = 0
                for line in iter(f.readline, b"\r\n"):
                    name, _, value = line.partition(b":")
                    if name.strip().lower() == b"content-length":
                        length = int(value)
                answers.append((status, f.read(length)))
    return answers


class JobRecordsTest(unittest.TestCase):
    def test_one_users_flood_of_job_posts_keeps_other_users_records(self):
        with Daemon("--workers", "1") as d:
            bob = post_from(d.port, "127.0.0.2", "/v1/jobs", sphere(0.5)).json()
            wait_until("bob's job", lambda: http_request(d.port, "GET", bob["url"],
                                                          source="127.0.0.2").json()["state"] == "done")
            # alice: more posts than the whole table holds (the mesh is cached by now, so
            # every job is finished at once)
            answers = pipelined_posts(d.port, "/v1/jobs", sphere(0.5), FLOOD_POSTS)
            self.assertEqual({st for st, _ in answers}, {202})
            ids = [json.loads(b)["id"] for _, b in answers]
            self.assertEqual(len(set(ids)), FLOOD_POSTS)
            # bob's record is still there, alice's own oldest are the ones that went
            again = http_request(d.port, "GET", bob["url"], source="127.0.0.2")
            self.assertEqual(again.status, 200)
            self.assertEqual(again.json()["state"], "done")
            first_kept = FLOOD_POSTS - USER_JOBS_KEPT
            for i, status in ((0, 404), (first_kept - 1, 404), (first_kept, 200), (-1, 200)):
                self.assertEqual(d.get("/v1/jobs/" + ids[i]).status, status, i)


def server_timing(r, name):
    """The duration (ms) of one Server-Timing entry."""
    for part in (r.header("Server-Timing") or "").split(","):
        k, _, v = part.strip().partition(";dur=")
        if k == name:
            return float(v)
    return None


def settled(d, users, busy, queued, timeout=60):
    """The metrics (one scrape) once the scheduler has settled: `busy` workers computing,
    `queued` computations waiting, and each of `users` computing -- so no preemption is still
    due (a user waiting with nothing running while another holds two workers). The two gauges
    alone are not enough: when the third user's two jobs both arrive before the pool thread
    wakes (a loaded machine), the first two users still hold two workers each, the gauges read
    4 busy and 2 queued, and the preemption that follows sends one job record back to "queued"
    until its worker is replaced: 3 running (CI on 3831115; reproduced every time by freezing
    the pool thread alone while the third user posts). The per-user gauges are read under the
    scheduler's lock, and the job records' states change in the same critical sections."""
    last = {}

    def check():
        m = last["m"] = d.metrics()
        running = [m.get(metric_key("isomesh_user_jobs", {"user": u, "state": "running"}), 0)
                   for u in users]
        return (m.get("isomesh_workers_busy") == busy and m.get("isomesh_queue_depth") == queued
                and min(running) >= 1 and sum(running) == busy)
    try:
        wait_until("%d workers busy, %d queued, each of %s computing" % (busy, queued, users),
                   check, timeout)
    except AssertionError as e:
        gauges = {k: v for k, v in last.get("m", {}).items()
                  if k.startswith(("isomesh_workers_", "isomesh_queue_depth", "isomesh_user_jobs",
                                   "isomesh_preemptions", "isomesh_worker_restarts"))}
        raise AssertionError("%s; last gauges %s\n%s" % (e, gauges, d.log()[-3000:])) from None
    return last["m"]


class HopelessUsersTest(unittest.TestCase):
    def test_long_requests_of_three_users_leave_a_worker_for_a_fourth(self):
        # 4 workers; 3 users (3 addresses) send 2 long jobs each: one user ends up with 2
        # workers, the others with 1 each (a user with nothing running who finds every worker
        # busy takes one back from a user holding two) -- every worker busy until its deadline
        with Daemon("--workers", "4", "--job-timeout", "60s") as d:
            users = ("127.0.0.2", "127.0.0.3", "127.0.0.4")
            jobs = []
            for user in users:
                for i in range(2):
                    r = post_from(d.port, user, "/v1/jobs", busy_work(len(jobs) + 1))
                    self.assertEqual(r.status, 202, r.body[:200])
                    jobs.append((user, r.json()))
            before = settled(d, users, busy=4, queued=2).get("isomesh_preemptions_total", 0)
            try:
                running = [u for u, j in jobs if http_request(d.port, "GET", j["url"], source=u)
                           .json()["state"] == "running"]
                self.assertEqual(len(running), 4)
                self.assertEqual(set(running), set(users))
                t0 = time.monotonic()
                small = post_from(d.port, "127.0.0.5", "/v1/mesh",
                                  {"expr": "x^2 + y^2 + z^2 - 0.25", "depth": {"max": 5},
                                   "max_error": None})
                took = time.monotonic() - t0
                self.assertEqual(small.status, 200, small.body[:300])
                self.assertLess(took, SMALL_BOUND_S)
                # one computation of the user holding two workers went back to its line
                self.assertEqual(d.metric("isomesh_preemptions_total"), before + 1)
                self.assertEqual(d.metric("isomesh_worker_restarts_total", reason="preempt"),
                                 before + 1)
                states = [http_request(d.port, "GET", j["url"], source=u).json()["state"]
                          for u, j in jobs]
                self.assertEqual(states.count("running") + states.count("queued"), 6, states)
                # and gets its worker back once the small request is done
                settled(d, users, busy=4, queued=2)
            finally:
                for u, j in jobs:
                    http_request(d.port, "DELETE", j["url"], source=u)

    def test_a_user_on_every_worker_keeps_half_of_them_while_another_user_waits(self):
        # the default --user-running (issue 17: "at most half the workers when others wait"):
        # alone, a user computes on all 4 workers; once another user waits, the first gives
        # workers back until it holds half of them (rounded up), the other user as many --
        # not fewer (a third job of the second user does not take one more), and not more
        # (two each, stable); when nobody else waits, every worker again
        with Daemon("--workers", "4", "--job-timeout", "60s") as d:
            def jobs_of(user, state):
                return d.metric("isomesh_user_jobs", user=user, state=state)
            alice = [post_from(d.port, "127.0.0.2", "/v1/jobs", busy_work(i + 1)).json()
                     for i in range(4)]
            bob = []
            try:
                wait_until("alice on every worker", lambda: jobs_of("127.0.0.2", "running") == 4)
                before = d.metric("isomesh_preemptions_total")
                bob = [post_from(d.port, "127.0.0.3", "/v1/jobs", busy_work(10 + i)).json()
                       for i in range(3)]
                wait_until("two workers each", lambda: jobs_of("127.0.0.2", "running") == 2
                           and jobs_of("127.0.0.3", "running") == 2)
                self.assertEqual(jobs_of("127.0.0.2", "queued"), 2)
                self.assertEqual(jobs_of("127.0.0.3", "queued"), 1)
                # one for a user with nothing running, one for a user below the half
                self.assertEqual(d.metric("isomesh_preemptions_total"), before + 2)
                for j in bob:
                    http_request(d.port, "DELETE", j["url"], source="127.0.0.3")
                wait_until("alice on every worker again",
                           lambda: jobs_of("127.0.0.2", "running") == 4)
                self.assertEqual(d.metric("isomesh_preemptions_total"), before + 2)
            finally:
                for u, js in (("127.0.0.2", alice), ("127.0.0.3", bob)):
                    for j in js:
                        http_request(d.port, "DELETE", j["url"], source=u)


class QueueDeadlineTest(unittest.TestCase):
    def test_the_deadline_counts_time_on_a_worker_not_the_wait_for_one(self):
        # one worker held by a long job until its 3 s deadline; a small request queued
        # behind it waits about that long, then computes in milliseconds: answered, not 504
        with Daemon("--workers", "1", "--job-timeout", "3s", "--queue-timeout", "30s") as d:
            blocker = d.post("/v1/jobs", busy_work(1)).json()
            wait_until("the blocker running", lambda: d.get(blocker["url"]).json()["state"] == "running")
            small = post_from(d.port, "127.0.0.2", "/v1/mesh",
                              {"expr": "x^2 + y^2 + z^2 - 0.25", "depth": {"max": 5}})
            self.assertEqual(small.status, 200, small.body[:300])
            self.assertGreater(server_timing(small, "queue"), 1000)  # it did wait
            self.assertEqual(d.get(blocker["url"]).json()["error"]["code"], "deadline_exceeded")

    def test_a_wait_past_the_queue_timeout_is_a_clear_503(self):
        with Daemon("--workers", "1", "--job-timeout", "60s", "--queue-timeout", "1s") as d:
            # a hopeless request is refused with its reason, and leaves the one worker free:
            # were it computing (until the 60 s deadline), the blocker below would fail its
            # 1 s queue deadline instead of running
            for path in ("/v1/mesh", "/v1/jobs"):
                r = post_from(d.port, "127.0.0.3", path, hopeless(3))
                if path == "/v1/jobs":
                    job = r.json()
                    r = wait_until("the hopeless job ending", lambda: (lambda j: j if j["state"]
                                   in ("failed", "done") else None)(http_request(
                                       d.port, "GET", job["url"], source="127.0.0.3").json()))
                    self.assertEqual(r["status"], 422, r)
                    err = r["error"]
                else:
                    self.assertEqual(r.status, 422, r.body[:300])
                    err = r.json()["error"]
                self.assertEqual(err["code"], "unresolvable", err)
                self.assertIn("faster than any cell can resolve", err["message"])
            blocker = d.post("/v1/jobs", busy_work(1)).json()
            try:
                wait_until("the blocker running",
                           lambda: d.get(blocker["url"]).json()["state"] == "running")
                t0 = time.monotonic()
                r = post_from(d.port, "127.0.0.2", "/v1/mesh", sphere(0.4))
                took = time.monotonic() - t0
                self.assertEqual(r.status, 503, r.body[:300])
                self.assertEqual(r.json()["error"]["code"], "queue_timeout")
                self.assertIn("--queue-timeout", r.json()["error"]["message"])
                self.assertIsNotNone(r.header("Retry-After"))
                self.assertGreater(took, 0.9)
                self.assertLess(took, 10)
                # the same for a job: failed with that error, the blocker untouched
                job = post_from(d.port, "127.0.0.2", "/v1/jobs", sphere(0.41)).json()
                got = wait_until("the job failing", lambda: (lambda j: j if j["state"] == "failed"
                                                             else None)(
                    http_request(d.port, "GET", job["url"], source="127.0.0.2").json()))
                self.assertEqual((got["status"], got["error"]["code"]), (503, "queue_timeout"))
                self.assertEqual(d.get(blocker["url"]).json()["state"], "running")
            finally:
                d.request("DELETE", blocker["url"])


if __name__ == "__main__":
    unittest.main()
