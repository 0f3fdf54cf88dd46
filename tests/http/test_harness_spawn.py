"""test_harness_spawn.py — the servers the tests start (harness.spawn_owned: isomeshd, redis-server,
nginx, stunnel) live in a session of their own and die with the thread that started them.

Why: a test that SIGSTOPs a daemon's worker (stack.pause_workers) or Redis must not share a
process group with the shell or runner above it. When a process group loses its last tie to its
session while one of its processes is stopped, the kernel sends SIGHUP and then SIGCONT to every
process in it (POSIX _exit(), "orphaned process group") — session 17's qflake loop saw both
daemons log `reload_ignored` and the paused worker run on, at the same millisecond, with no one
signalling by name. The test below builds that situation with small stand-ins (a sleeping
python "server" that records SIGHUP, a `sleep` "worker" that ignores it) and checks that the
server started through spawn_owned is not reached; with a plain subprocess.Popen, as the harness
used to start them, it fails here: the server records SIGHUP and the worker runs again.
Every process is stopped by the pid this test holds. Takes about a second."""
import os
import signal
import subprocess
import sys
import tempfile
import time
import unittest

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from harness import spawn_owned, process_alive  # noqa: E402

HERE = os.path.dirname(os.path.abspath(__file__))

# The "server": records SIGHUP in its directory, starts a "worker" that ignores SIGHUP (as a
# worker's sigwait thread would take it elsewhere), writes both pids, then waits to be stopped.
SERVER = r"""
import os, signal, subprocess, sys, time
d = sys.argv[1]
signal.signal(signal.SIGHUP, lambda *a: open(os.path.join(d, "hup"), "a").write("hup\n"))
w = subprocess.Popen(["sleep", "60"], preexec_fn=lambda: signal.signal(signal.SIGHUP, signal.SIG_IGN))
with open(os.path.join(d, "pids.tmp"), "w") as f:
    f.write("%d %d\n" % (os.getpid(), w.pid))
os.rename(os.path.join(d, "pids.tmp"), os.path.join(d, "pids"))
time.sleep(60)
"""

# The "test": starts the server through spawn_owned, writes its own pid, then waits.
TEST = r"""
import os, subprocess, sys, time
sys.path.insert(0, sys.argv[2])
from harness import spawn_owned
d = sys.argv[1]
spawn_owned([sys.executable, "-c", sys.argv[3], d], stdin=subprocess.DEVNULL)
with open(os.path.join(d, "test.tmp"), "w") as f:
    f.write("%d\n" % os.getpid())
os.rename(os.path.join(d, "test.tmp"), os.path.join(d, "test"))
time.sleep(60)
"""

# The "wrapper" above the test (a job's subshell): runs it in the wrapper's own process group.
LINK = r"""
import subprocess, sys, time
subprocess.Popen(sys.argv[1:])
time.sleep(60)
"""


def state(pid):
    with open("/proc/%d/stat" % pid) as f:
        return f.read().rsplit(")", 1)[1].split()[0]


def wait_for(pred, timeout=20):
    deadline = time.time() + timeout
    while not pred():
        if time.time() > deadline:
            return False
        time.sleep(0.02)
    return True


def kill_quietly(pid):
    try:
        os.kill(pid, signal.SIGKILL)
    except ProcessLookupError:
        pass


class SpawnOwnedTest(unittest.TestCase):
    def test_a_server_has_a_session_of_its_own(self):
        p = spawn_owned(["sleep", "30"], stdin=subprocess.DEVNULL)
        try:
            self.assertEqual(os.getsid(p.pid), p.pid)
            self.assertEqual(os.getpgid(p.pid), p.pid)
            self.assertNotEqual(os.getsid(p.pid), os.getsid(0))
        finally:
            p.kill()
            p.wait(10)

    def orphan_a_group_with_a_stopped_worker(self):
        """LINK (its own group) -> TEST -> SERVER -> WORKER; WORKER stopped, then LINK killed:
        TEST's group loses its tie to the session. Returns (server got SIGHUP, worker state)."""
        tmp = tempfile.TemporaryDirectory()
        d = tmp.name
        link = subprocess.Popen([sys.executable, "-c", LINK, sys.executable, "-c", TEST, d, HERE,
                                 SERVER], stdin=subprocess.DEVNULL, process_group=0)
        pids = []
        try:
            self.assertTrue(wait_for(lambda: os.path.exists(os.path.join(d, "pids")) and
                                     os.path.exists(os.path.join(d, "test"))))
            with open(os.path.join(d, "test")) as f:
                pids.append(int(f.read()))
            with open(os.path.join(d, "pids")) as f:
                server, worker = map(int, f.read().split())
            pids += [server, worker]
            os.kill(worker, signal.SIGSTOP)  # as pause_workers does
            self.assertTrue(wait_for(lambda: state(worker) == "T"))
            link.kill()  # the wrapper goes: the group is orphaned
            link.wait(10)
            time.sleep(0.3)  # the kernel signals at the exit itself; a margin for the handler
            hupped = os.path.exists(os.path.join(d, "hup"))
            worker_state = state(worker)
            # the tie: the test's process gone, its owned server is sent SIGTERM
            kill_quietly(pids[0])
            self.assertTrue(wait_for(lambda: not process_alive(server)),
                            "the server outlived the test that started it")
            return hupped, worker_state
        finally:
            if link.poll() is None:
                link.kill()
                link.wait(10)
            for pid in pids:  # only the pids this test started
                kill_quietly(pid)
            tmp.cleanup()

    def test_an_owned_server_is_not_hupped_when_the_test_group_is_orphaned(self):
        hupped, worker_state = self.orphan_a_group_with_a_stopped_worker()
        self.assertFalse(hupped, "the server got SIGHUP")
        self.assertEqual(worker_state, "T", "the paused worker was continued")


if __name__ == "__main__":
    unittest.main()
