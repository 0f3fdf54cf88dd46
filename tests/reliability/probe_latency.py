#!/usr/bin/env python3
"""probe_latency.py — a latency probe in its own process (so that the test process's other
threads, and its interpreter lock, never delay it): GET path on 127.0.0.1:port on a fresh
connection, again and again until its standard input closes. Prints its first sample as a
line of JSON at once (the caller then knows it runs), the others as one JSON list at the end;
a sample is [start on the CLOCK_MONOTONIC clock every process shares, seconds, answered 200].

Usage: probe_latency.py PORT PATH"""
import http.client
import json
import select
import sys
import time

PAUSE_S = 0.005  # between requests: ~100-200 samples a second on an idle machine
TIMEOUT_S = 60   # a bound against hanging, far beyond any answer being judged


def sample(port, path):
    t0 = time.monotonic()
    try:
        c = http.client.HTTPConnection("127.0.0.1", port, timeout=TIMEOUT_S)
        c.request("GET", path)
        ok = c.getresponse().status == 200
        c.close()
    except OSError:
        ok = False
    return [t0, time.monotonic() - t0, ok]


def main():
    port, path = int(sys.argv[1]), sys.argv[2]
    print(json.dumps(sample(port, path)), flush=True)
    samples = []
    while not select.select([sys.stdin], [], [], PAUSE_S)[0]:  # readable: closed
        samples.append(sample(port, path))
    print(json.dumps(samples))


if __name__ == "__main__":
    main()
