"""test_cluster_scripts.py — the cluster queue's Lua scripts (server/isomeshd/cluster.c, taken
through the C preprocessor: the daemon's own text) run step by step against a real Redis, so
that the order of heartbeats and takes is the test's, not the machine's:

* a user over its share gives back the computation it started last (the least work lost, as
  one daemon's scheduler chooses), not whichever heartbeat comes first: the older one's
  heartbeat keeps it while the newer one may go (before: the older one went);
* the given-back entry is its user's next: after the waiting user's entry, the freed worker
  takes it before the user's entry queued behind it (before: after it);
* of users tied for the fewest running, the one served longest ago is next: a user whose
  computations all end before any daemon takes again (a loaded machine runs every FINISH
  first) does not take the worker from a user who waited for it, whatever the daemon's turn
  (before: the turn chose, and turn 0 gave it to the first user);
* the users' kept counts (P run, P nwait, P wait) say at every step what the streams hold."""
import os
import sys
import unittest

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import stack  # noqa: E402

SKIP = stack.missing_programs()
P = "isomesh:v1:"
TTL = "3600000"


@unittest.skipIf(SKIP, SKIP)
class ClusterScriptsTest(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.lua = stack.cluster_scripts()
        cls.redis = stack.Redis().start()

    @classmethod
    def tearDownClass(cls):
        cls.redis.cleanup()

    def r(self, *args):
        return self.redis.command(*args)

    def enqueue(self, user, name):
        got = self.r("EVAL", self.lua["ENQUEUE_LUA"], 3, P + "q:" + user, P + "job:" + name,
                     P + "ulim", user, "100", name, "k", "drc", "{}", "0", TTL, "origin", P)
        return got[0].decode()

    def take(self, daemon, turn=0):
        got = self.r("EVAL", self.lua["TAKE_LUA"], 2, P + "wait", P + "run", P, daemon, TTL,
                     str(turn), "0", TTL)
        if not got:
            return None
        fields = dict(zip(got[3][::2], got[3][1::2]))
        return {"user": got[0].decode(), "stream": got[1].decode(), "id": got[2].decode(),
                "name": fields[b"name"].decode(), "daemon": daemon}

    def beat(self, e):
        return self.r("EVAL", self.lua["HEARTBEAT_LUA"], 2, e["stream"], P + "job:" + e["name"],
                      e["daemon"], e["id"], "0.5", TTL, P, e["name"], "0", "1", e["user"])

    def finish(self, e):
        self.r("EVAL", self.lua["FINISH_LUA"], 2, e["stream"], P + "job:" + e["name"], e["id"],
               "done", "200", "", TTL, P)

    def kept(self):
        run = self.r("HGETALL", P + "run")
        nwait = self.r("HGETALL", P + "nwait")
        wait = self.r("ZRANGE", P + "wait", 0, -1, "WITHSCORES")
        as_dict = lambda flat: {k.decode(): int(float(v)) for k, v in zip(flat[::2], flat[1::2])}
        return as_dict(run), as_dict(nwait), as_dict(wait)

    def test_the_newest_computation_is_given_back_and_taken_again_first(self):
        self.r("FLUSHALL")
        for d in ("d1", "d2"):  # two daemons of one worker each, alive
            self.r("SET", P + "alive:" + d, "1")
            self.r("HSET", P + "nworkers", d, "1")
        for name in ("a", "b", "c"):
            self.enqueue("u", name)
        older, newer = self.take("d1"), self.take("d2")
        self.assertEqual((older["name"], newer["name"]), ("a", "b"))
        self.assertEqual(self.kept(), ({"u": 2}, {"u": 1}, {"u": 2}))
        # started on Redis's clock: b after a (set apart: two takes may share a millisecond)
        self.r("HSET", P + "job:a", "started_ms", "1000")
        self.r("HSET", P + "job:b", "started_ms", "2000")
        # heartbeats while nobody else waits: kept, each saying it may go
        self.assertEqual((self.beat(older), self.beat(newer)), (1, 1))
        self.enqueue("v", "w")
        self.assertEqual(self.kept(), ({"u": 2}, {"u": 1, "v": 1}, {"u": 2, "v": 0}))
        # u holds both workers while v waits with none: the older one's heartbeat keeps it
        self.assertEqual(self.beat(older), 1)
        self.assertEqual(self.beat(newer), 3)
        job_b = self.r("HGETALL", P + "job:b")
        job_b = dict(zip(job_b[::2], job_b[1::2]))
        self.assertEqual((job_b[b"state"], job_b[b"stream"]), (b"queued", (P + "r:u").encode()))
        self.assertEqual(self.kept(), ({"u": 1}, {"u": 2, "v": 1}, {"u": 1, "v": 0}))
        # the freed worker: v first (fewest running), then, v's done, u's given-back b before c
        w = self.take("d2")
        self.assertEqual((w["user"], w["name"]), ("v", "w"))
        self.r("EVAL", self.lua["FINISH_LUA"], 2, w["stream"], P + "job:w", w["id"], "done",
               "200", "", TTL, P)
        again = self.take("d2")
        self.assertEqual((again["user"], again["name"], again["stream"]), ("u", "b", P + "r:u"))
        self.assertEqual(self.kept(), ({"u": 2}, {"u": 1}, {"u": 2}))
        # both end; c is taken last; then nothing is left anywhere
        for e in (older, again):
            self.r("EVAL", self.lua["FINISH_LUA"], 2, e["stream"], P + "job:" + e["name"],
                   e["id"], "done", "200", "", TTL, P)
        last = self.take("d1")
        self.assertEqual(last["name"], "c")
        self.r("EVAL", self.lua["FINISH_LUA"], 2, last["stream"], P + "job:c", last["id"],
               "done", "200", "", TTL, P)
        self.assertEqual(self.kept(), ({}, {}, {}))
        self.assertEqual(self.r("KEYS", P + "[qr]:*"), [])
        self.assertIsNone(self.take("d1"))

    def test_of_users_tied_for_fewest_running_the_one_served_longest_ago_is_next(self):
        for turn in range(3):  # whatever the daemon's turn
            self.r("FLUSHALL")
            for name in ("a", "b", "c", "d"):
                self.enqueue("u", name)
            held = [self.take(d) for d in ("d1", "d2", "d3")]
            self.enqueue("v", "w")
            for e in held:  # every one ends before any daemon takes again
                self.finish(e)
            self.assertEqual(self.kept(), ({}, {"u": 1, "v": 1}, {"u": 0, "v": 0}))
            first = self.take("d1", turn)
            self.assertEqual((turn, first["user"]), (turn, "v"))
            # now u runs fewer: its last one next, then nothing
            self.assertEqual(self.take("d2", turn)["name"], "d")
            self.assertIsNone(self.take("d3", turn))
        # a user with nothing left is forgotten (its served count too)
        for e in (first, {"stream": P + "q:u", "name": "d", "id": self.r(
                "XPENDING", P + "q:u", "workers", "-", "+", 1)[0][0].decode()}):
            self.finish(e)
        self.assertEqual(self.r("HGETALL", P + "served"), [])

    def test_a_job_deleted_while_its_daemon_looked_dead_stays_canceled(self):
        # A DELETE through another daemon flags the job's record. When the daemon holding the
        # job is alive, it takes the flag back if it finds the job finished (it finished
        # first); when the DELETE found it dead (cut off past a lock lifetime: no alive key),
        # the DELETE was the cancel and the flag is final: a computation started over there
        # for other requests that finishes the job before the daemon takes its deleted set
        # must not turn it into done (before: the flag went, the job read done after its
        # client was told canceled — test_cluster_queue's cut-off test at load 20).
        for alive in (True, False):
            d, job = "dA%d" % alive, "j%d" % alive
            rec = P + "jobrec:" + job
            self.r("HSET", rec, "user", "u", "daemon", d)  # no key: no computation looked at
            if alive:
                self.r("SET", P + "alive:" + d, "1")
            for _ in range(2):  # a retried DELETE changes nothing
                self.assertEqual(self.r("EVAL", self.lua["JOB_DELETE_LUA"], 1, rec, P, job,
                                        TTL, "0"), 1)
                self.assertEqual(self.r("HGET", rec, "cancel"), b"1" if alive else b"final")
                self.assertEqual(self.r("SMEMBERS", P + "deleted:" + d), [job.encode()])
                self.r("SET", P + "alive:" + d, "1")  # the cut-off daemon is back
            # its daemon takes the set and finds the job finished
            self.assertEqual(self.r("EVAL", self.lua["UNDELETE_LUA"], 1, rec),
                             1 if alive else 0)
            self.assertEqual(self.r("HGET", rec, "cancel"), None if alive else b"final")


if __name__ == "__main__":
    unittest.main()
