/* worker.h — `isomesh --worker`: the process isomeshd keeps running in its pool. It reads
 * REQUEST frames (proto/frame.h) on in_fd, runs each through the pipeline, and answers with
 * PROGRESS frames while it works and one RESULT frame per job on out_fd. */
#ifndef ISM_WORKER_H
#define ISM_WORKER_H

/* Runs the worker loop until in_fd reaches end of stream (returns 0) or the channel breaks
 * (a malformed, oversized or unexpected frame, a failed write: returns 1, after logging the
 * reason on stderr). When out_fd is stdout, the channel moves to a private descriptor and
 * stdout is pointed at stderr, so a stray printf can never corrupt a frame. */
int ism_worker_main(int in_fd, int out_fd);

#endif
