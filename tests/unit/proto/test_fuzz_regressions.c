/* test_fuzz_regressions.c — the proto fuzz targets' inputs replayed in `make test`: every
 * seed (tests/fuzz/corpus/{request,frame}/) and every input that once crashed a target or
 * broke one of its invariants (tests/fuzz/regressions/{request,frame}/, one file per bug)
 * goes through the same checks as under libFuzzer (the target files are included here), so
 * a fixed bug stays fixed. A broken check fails the test and names the input. */
#include "tests/fuzz/replay_criterion.h"
#include "tests/fuzz/fuzz_request.c"
#include "tests/fuzz/fuzz_frame.c"

Test(fuzz_regressions, request_seeds)
{
    replay("tests/fuzz/corpus/request", ism_fuzz_request, 0);
}

Test(fuzz_regressions, request_regressions)
{
    replay("tests/fuzz/regressions/request", ism_fuzz_request, 1);
}

Test(fuzz_regressions, frame_seeds)
{
    replay("tests/fuzz/corpus/frame", ism_fuzz_frame, 0);
}

Test(fuzz_regressions, frame_regressions)
{
    replay("tests/fuzz/regressions/frame", ism_fuzz_frame, 1);
}
