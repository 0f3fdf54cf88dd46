"""test_static.py — the viewer's files and three.js as isomeshd serves them: index pages, MIME
types (module scripts as text/javascript, wasm as application/wasm), validators and 304, no
directory listing, nothing outside the web root whatever the URL says (.., %2e%2e, encoded
slashes, doubled slashes, NUL, backslashes, symlinks pointing out), and /vendor/three/ limited
to build/ and examples/jsm/."""
import os
import shutil
import sys
import tempfile
import unittest

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from harness import ROOT, Daemon  # noqa: E402

INDEX = b"<!doctype html><title>isomesh test viewer</title>\n"
APP = b"export const answer = 42;\n"


def write(path, data):
    os.makedirs(os.path.dirname(path), exist_ok=True)
    with open(path, "wb") as f:
        f.write(data)


class StaticTest(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.tmp = tempfile.mkdtemp(prefix="isomeshd_web_")
        web = cls.web = os.path.join(cls.tmp, "web")
        write(os.path.join(web, "index.html"), INDEX)
        write(os.path.join(web, "js", "app.js"), APP)
        write(os.path.join(web, "js", "worker.mjs"), APP)
        write(os.path.join(web, "style.css"), b"body { margin: 0 }\n")
        write(os.path.join(web, "data", "surfaces.json"), b"{}\n")
        write(os.path.join(web, "empty", "readme.txt"), b"no index here\n")
        write(os.path.join(web, ".secret"), b"hidden\n")
        write(os.path.join(cls.tmp, "outside.txt"), b"outside the root\n")
        os.symlink(os.path.join(cls.tmp, "outside.txt"), os.path.join(web, "leak.txt"))
        os.symlink("/", os.path.join(web, "rootdir"))
        os.symlink("..", os.path.join(web, "up"))
        os.symlink("index.html", os.path.join(web, "home.html"))  # inside: allowed
        three = os.path.join(web, "node_modules", "three")
        write(os.path.join(three, "package.json"), b'{"name": "three"}\n')
        write(os.path.join(three, "build", "three.module.js"), APP)
        write(os.path.join(three, "examples", "jsm", "libs", "draco", "draco_decoder.wasm"),
              b"\0asm\1\0\0\0")
        write(os.path.join(three, "src", "Three.js"), APP)
        cls.d = Daemon("--workers", "1", web_root=web)
        try:
            cls.d.start()
        except Exception:
            cls.d.cleanup()
            raise

    @classmethod
    def tearDownClass(cls):
        cls.d.cleanup()
        shutil.rmtree(cls.tmp, ignore_errors=True)

    def test_index_and_types(self):
        for path in ("/", "/index.html", "/home.html"):
            r = self.d.get(path)
            self.assertEqual(r.status, 200, path)
            self.assertEqual(r.body, INDEX)
            self.assertEqual(r.header("Content-Type"), "text/html; charset=utf-8")
        cases = {"/js/app.js": "text/javascript; charset=utf-8",
                 "/js/worker.mjs": "text/javascript; charset=utf-8",
                 "/style.css": "text/css; charset=utf-8",
                 "/data/surfaces.json": "application/json",
                 "/empty/readme.txt": "text/plain; charset=utf-8"}
        for path, ctype in cases.items():
            r = self.d.get(path)
            self.assertEqual(r.status, 200, path)
            self.assertEqual(r.header("Content-Type"), ctype, path)
            self.assertEqual(r.header("X-Content-Type-Options"), "nosniff")
        head = self.d.request("HEAD", "/js/app.js")
        self.assertEqual(head.status, 200)
        self.assertEqual(head.body, b"")
        self.assertEqual(int(head.header("Content-Length")), len(APP))

    def test_validator_and_304(self):
        r = self.d.get("/js/app.js")
        etag = r.header("ETag")
        self.assertTrue(etag)
        again = self.d.get("/js/app.js", headers={"If-None-Match": etag})
        self.assertEqual(again.status, 304)
        self.assertEqual(again.body, b"")

    def test_no_directory_listing(self):
        for path in ("/empty/", "/empty", "/js/", "/data"):
            self.assertEqual(self.d.get(path).status, 404, path)

    def test_traversal_and_escapes_are_404(self):
        attempts = [
            "/../outside.txt", "/js/../../outside.txt", "/%2e%2e/outside.txt",
            "/%2E%2E/outside.txt", "/js/%2e%2e/%2e%2e/outside.txt", "/..%2foutside.txt",
            "/js%2f..%2f..%2foutside.txt", "//outside.txt", "/js//app.js",
            "/index.html%00.png", "/js/app.js%00", "/..\\outside.txt", "/%5c..%5coutside.txt",
            "/.secret", "/js/./app.js", "/./index.html", "/leak.txt", "/rootdir/etc/passwd",
            "/up/outside.txt", "/up/web/index.html", "/rootdir/", "/%", "/%zz",
            "/node_modules/three/package.json", "/node_modules/three/build/three.module.js",
        ]
        for path in attempts:
            status = self.d.raw(b"GET " + path.encode() + b" HTTP/1.1\r\nHost: x\r\n\r\n")
            self.assertIn(status, (400, 404), path)
            self.assertNotEqual(status, 200, path)

    def test_vendor_is_limited_to_build_and_jsm(self):
        r = self.d.get("/vendor/three/build/three.module.js")
        self.assertEqual(r.status, 200)
        self.assertEqual(r.header("Content-Type"), "text/javascript; charset=utf-8")
        w = self.d.get("/vendor/three/examples/jsm/libs/draco/draco_decoder.wasm")
        self.assertEqual(w.status, 200)
        self.assertEqual(w.header("Content-Type"), "application/wasm")
        for path in ("/vendor/three/package.json", "/vendor/three/src/Three.js",
                     "/vendor/three/build/../package.json", "/vendor/three/build/%2e%2e/package.json",
                     "/vendor/three/examples/jsm/../../package.json", "/vendor/three/",
                     "/vendor/three/build/", "/vendor/", "/vendor/three"):
            status = self.d.raw(b"GET " + path.encode() + b" HTTP/1.1\r\nHost: x\r\n\r\n")
            self.assertIn(status, (400, 404), path)


class RealViewerTest(unittest.TestCase):
    """The checkout's own web/ and its npm-installed three.js."""

    def test_three_from_node_modules(self):
        three = os.path.join(ROOT, "web", "node_modules", "three")
        if not os.path.isdir(three):
            self.skipTest("web/node_modules not installed (make web-deps)")
        with Daemon("--workers", "1") as d:
            r = d.get("/vendor/three/build/three.module.js")
            self.assertEqual(r.status, 200)
            self.assertEqual(r.header("Content-Type"), "text/javascript; charset=utf-8")
            with open(os.path.join(three, "build", "three.module.js"), "rb") as f:
                self.assertEqual(r.body, f.read())
            w = d.get("/vendor/three/examples/jsm/libs/draco/draco_decoder.wasm")
            self.assertEqual(w.status, 200)
            self.assertEqual(w.header("Content-Type"), "application/wasm")
            self.assertEqual(w.body[:4], b"\0asm")
            loader = d.get("/vendor/three/examples/jsm/loaders/DRACOLoader.js")
            self.assertEqual(loader.status, 200)
            if os.path.exists(os.path.join(ROOT, "web", "index.html")):
                index = d.get("/")
                self.assertEqual(index.status, 200)
                self.assertEqual(index.header("Content-Type"), "text/html; charset=utf-8")


if __name__ == "__main__":
    unittest.main()
