// gpu.js — waiting for the GPU without blocking the page: a WebGL2 fence after the commands
// issued so far, polled from timer tasks (a fence's status changes only between tasks), so
// input events and animation frames run meanwhile. Used by the occlusion batches and the
// viewer's frame timing.

// How often a fence is polled while the GPU works (ms).
const POLL_MS = 4;

// Resolves once the GPU has done every command issued on gl so far.
export function gpuDone(gl) {
  const sync = gl.fenceSync(gl.SYNC_GPU_COMMANDS_COMPLETE, 0);
  gl.flush();
  if (!sync) return Promise.resolve();   // context lost: nothing to wait for
  return new Promise((resolve) => {
    const poll = () => {
      if (gl.clientWaitSync(sync, 0, 0) === gl.TIMEOUT_EXPIRED) {
        setTimeout(poll, POLL_MS);
        return;
      }
      gl.deleteSync(sync);
      resolve();
    };
    setTimeout(poll, 0);
  });
}
