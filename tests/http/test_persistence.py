"""test_persistence.py — the disk cache through daemon restarts: a mesh computed before a
restart is served from disk after it without computing (also another format of it, computed
from the stored request); a flipped byte in a cache file is detected, the entry dropped and
counted, and the mesh recomputed and correct; an unwritable cache directory still serves
every request and counts the failed stores; a large cached body is sent from its disk file
(sendfile), byte for byte the body computed, and from memory while the file changed moments
ago or when it does not match: a wrong length, or a byte flipped on disk after it was sent from
(the file is then dropped as damaged); a mid-size body goes from memory (its header block in
the same send as the body) however many connections are open when libmicrohttpd answers it
(--own-sender=off: the own sender sends every cached mesh from its file). Every test runs with
the own sender (the default) and without it (PersistenceWithoutOwnSender)."""
import glob
import os
import shutil
import socket
import sys
import tempfile
import time
import unittest

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from harness import Daemon, draco_counts, http_request, sphere, wait_until  # noqa: E402

SENDFILE_MIN = 1 << 20  # server/isomeshd/respond.c: smaller bodies are copied
LARGE = {"preset": "gyroid-ball", "depth": {"max": 6}, "max_error": None,
         "output": {"format": "stl"}}
MID = {"preset": "sphere", "depth": {"max": 6}, "max_error": None,
       "output": {"format": "stl"}}  # 269 KB (the depth path: the default bound's is 53 KB)
# respond.c sent bodies from 64 KB by sendfile once this many connections were open (until
# 2026-11-27): libmicrohttpd then pushes the header block alone, which bbr makes expensive
BUSY_CONNECTIONS = 128


class PersistenceTest(unittest.TestCase):
    MODE = ()  # flags every daemon gets: the own sender, the default

    def setUp(self):
        self.tmp = tempfile.mkdtemp(prefix="isomeshd_persist_")
        self.cache = os.path.join(self.tmp, "cache")

    def tearDown(self):
        shutil.rmtree(self.tmp, ignore_errors=True)

    def cache_file(self, key, ext):
        hits = glob.glob(os.path.join(self.cache, "**", "%s.%s" % (key, ext)), recursive=True)
        self.assertEqual(len(hits), 1, "cache file %s.%s not found once" % (key, ext))
        return hits[0]

    def get_sent_from_file(self, d, url):
        """GETs url until an answer is sent from its cache file (bounded); that answer."""
        got = []

        def from_file():
            sent = d.metric("isomesh_sendfile_responses_total")
            got.append(d.get(url))
            return d.metric("isomesh_sendfile_responses_total") == sent + 1
        wait_until("an answer sent from the file", from_file)
        return got[-1]

    def test_restart_serves_from_disk_and_detects_a_flipped_byte(self):
        req = sphere(0.93)
        with Daemon("--workers", "1", *self.MODE, cache_dir=self.cache) as d:
            first = d.post("/v1/mesh", req)
            self.assertEqual(first.status, 200)
            self.assertEqual(first.header("X-Cache"), "miss")
            key = first.header("ETag").strip('"')
            stats = d.get("/v1/meshes/%s/stats" % key).json()
            rc = d.stop()
            self.assertEqual(rc, 0)

        # restart: served from disk, nothing computed
        with Daemon("--workers", "1", *self.MODE, cache_dir=self.cache) as d:
            got = d.get("/v1/meshes/%s.drc" % key)
            self.assertEqual(got.status, 200)
            self.assertEqual(got.header("X-Cache"), "hit")
            self.assertEqual(got.body, first.body)
            again = d.post("/v1/mesh", req)
            self.assertEqual(again.header("X-Cache"), "hit")
            self.assertEqual(d.get("/v1/meshes/%s/stats" % key).json(), stats)
            self.assertEqual(d.metric("isomesh_computations_started_total"), 0)
            self.assertGreaterEqual(d.metric("isomesh_cache_tier_hits_total", tier="disk"), 1)
            # a format never asked for before the restart: computed from the stored request
            glb = d.get("/v1/meshes/%s.glb" % key)
            self.assertEqual(glb.status, 200)
            self.assertEqual(glb.header("X-Cache"), "miss")
            self.assertEqual(glb.body[:4], b"glTF")
            self.assertEqual(d.metric("isomesh_computations_started_total"), 1)
            self.assertEqual(d.stop(), 0)

        # flip one byte in the middle of the stored Draco file
        path = self.cache_file(key, "drc")
        with open(path, "r+b") as f:
            f.seek(os.path.getsize(path) // 2)
            b = f.read(1)
            f.seek(-1, os.SEEK_CUR)
            f.write(bytes([b[0] ^ 0x01]))
        with Daemon("--workers", "1", *self.MODE, cache_dir=self.cache) as d:
            got = d.get("/v1/meshes/%s.drc" % key)
            self.assertEqual(got.status, 200)
            self.assertEqual(got.header("X-Cache"), "miss")
            self.assertEqual(got.body, first.body)  # recomputed, deterministic
            verts, faces = draco_counts(got.body)
            self.assertGreater(verts, 0)
            self.assertGreater(faces, 0)
            self.assertEqual(d.metric("isomesh_cache_corrupt_total", tier="disk"), 1)
            self.assertEqual(d.metric("isomesh_computations_started_total"), 1)
            wait_until("the drop logged", lambda: "cache_corrupt_entry_dropped" in d.log())
            self.assertEqual(d.get("/v1/meshes/%s.drc" % key).header("X-Cache"), "hit")
            self.assertEqual(d.stop(), 0)
        # and the rewritten file is whole again
        with Daemon("--workers", "1", *self.MODE, cache_dir=self.cache) as d:
            self.assertEqual(d.get("/v1/meshes/%s.drc" % key).header("X-Cache"), "hit")
            self.assertEqual(d.metric("isomesh_cache_corrupt_total", tier="disk"), 0)

    def test_a_large_cached_body_is_sent_from_its_disk_file(self):
        with Daemon("--workers", "1", *self.MODE, cache_dir=self.cache) as d:
            first = d.post("/v1/mesh", LARGE)
            self.assertEqual(first.status, 200)
            self.assertGreater(len(first.body), SENDFILE_MIN)
            key = first.header("ETag").strip('"')
            url = "/v1/meshes/%s.stl" % key
            wait_until("the file on disk", lambda: glob.glob(
                os.path.join(self.cache, "**", "%s.stl" % key), recursive=True))
            path = self.cache_file(key, "stl")
            wait_until("the file complete",
                       lambda: os.path.getsize(path) == len(first.body) + 24)
            # a file changed moments ago is not sent from (nor compared, file_memo.h): each
            # GET goes from memory until it has settled, then from the file
            got = self.get_sent_from_file(d, url)
            self.assertEqual(got.status, 200)
            self.assertEqual(got.body, first.body)
            self.assertEqual(got.header("Content-Type"), first.header("Content-Type"))
            head = http_request(d.port, "HEAD", url)
            self.assertEqual(int(head.header("Content-Length")), len(first.body))
            self.assertEqual(d.post("/v1/mesh", LARGE)
                             .body, first.body)  # a synchronous hit too
            sent = d.metric("isomesh_sendfile_responses_total")
            # a file that does not hold exactly these bytes' length is not used
            with open(path, "ab") as f:
                f.write(b"x")
            again = d.get(url)
            self.assertEqual(again.body, first.body)
            self.assertEqual(d.metric("isomesh_sendfile_responses_total"), sent)
            # cut back to them, it is (compared again, since it changed)
            os.truncate(path, len(first.body) + 24)
            self.assertEqual(self.get_sent_from_file(d, url).body, first.body)
            sent = d.metric("isomesh_sendfile_responses_total")
            # a byte flipped in it: never sent, dropped as damaged (once it has settled), and
            # the body comes from memory, byte for byte the one computed
            with open(path, "r+b") as f:
                f.seek(os.path.getsize(path) // 2)
                b = f.read(1)
                f.seek(-1, os.SEEK_CUR)
                f.write(bytes([b[0] ^ 0x01]))

            def dropped():
                again = d.get(url)
                self.assertEqual(again.status, 200)
                self.assertEqual(again.body, first.body)
                self.assertEqual(d.metric("isomesh_sendfile_responses_total"), sent)
                return d.metric("isomesh_cache_corrupt_total", tier="disk") == 1
            wait_until("the damaged file found", dropped)
            # the log comes through a pipe read by a thread: the line may follow the answer
            wait_until("the drop logged", lambda: "cache_corrupt_entry_dropped" in d.log())
            self.assertFalse(os.path.exists(path))

    def test_a_mid_size_body_goes_from_memory_with_many_connections_open(self):
        # respond.c's rule: libmicrohttpd's answers (the own sender's always go by sendfile)
        with Daemon("--workers", "1", "--own-sender=off", cache_dir=self.cache) as d:
            first = d.post("/v1/mesh", MID)
            self.assertEqual(first.status, 200)
            self.assertTrue(64 << 10 <= len(first.body) < SENDFILE_MIN, len(first.body))
            key = first.header("ETag").strip('"')
            url = "/v1/meshes/%s.stl" % key
            wait_until("the file on disk", lambda: glob.glob(
                os.path.join(self.cache, "**", "%s.stl" % key), recursive=True))
            path = self.cache_file(key, "stl")
            wait_until("the file complete",
                       lambda: os.path.getsize(path) == len(first.body) + 24)
            idle = []
            try:
                for _ in range(BUSY_CONNECTIONS + 8):
                    idle.append(socket.create_connection(("127.0.0.1", d.port), timeout=10))
                wait_until("the connections counted",
                           lambda: d.metric("isomesh_connections") >= BUSY_CONNECTIONS + 8)
                sent = d.metric("isomesh_sendfile_responses_total")
                # past file_memo.c's settling time (3 s even for whole-second file times): the
                # old rule sent from the file by then
                until = time.time() + 3.5
                while True:
                    got = d.get(url)
                    self.assertEqual(got.status, 200)
                    self.assertEqual(got.body, first.body)
                    self.assertEqual(d.metric("isomesh_sendfile_responses_total"), sent)
                    if time.time() > until:
                        break
                    time.sleep(0.25)
            finally:
                for c in idle:
                    c.close()

    def test_unwritable_cache_dir_still_serves(self):
        blocker = os.path.join(self.tmp, "file")
        with open(blocker, "w") as f:
            f.write("a file where the cache directory should be\n")
        with Daemon("--workers", "1", *self.MODE, cache_dir=os.path.join(blocker, "cache")) as d:
            first = d.post("/v1/mesh", sphere(0.94))
            self.assertEqual(first.status, 200)
            self.assertGreater(draco_counts(first.body)[1], 0)
            self.assertEqual(d.post("/v1/mesh", sphere(0.94)).header("X-Cache"), "hit")  # memory
            self.assertGreater(d.metric("isomesh_cache_store_failures_total", tier="disk"), 0)
            self.assertIn("cache_dir_unusable", d.log())

    def test_no_memory_tier_reads_disk_every_time(self):
        with Daemon("--workers", "1", *self.MODE, "--cache-mem", "0", cache_dir=self.cache) as d:
            first = d.post("/v1/mesh", sphere(0.95))
            key = first.header("ETag").strip('"')
            for _ in range(3):
                r = d.get("/v1/meshes/%s.drc" % key)
                self.assertEqual(r.header("X-Cache"), "hit")
                self.assertEqual(r.body, first.body)
            self.assertGreaterEqual(d.metric("isomesh_cache_tier_hits_total", tier="disk"), 3)
            self.assertEqual(d.metric("isomesh_computations_started_total"), 1)
            self.assertEqual(d.stop(), 0)  # a clean stop flushes the writes
        self.cache_file(key, "drc")


class PersistenceWithoutOwnSender(PersistenceTest):
    MODE = ("--own-sender=off",)  # libmicrohttpd answers every request
    # runs without the own sender in PersistenceTest already
    test_a_mid_size_body_goes_from_memory_with_many_connections_open = None


if __name__ == "__main__":
    unittest.main()
