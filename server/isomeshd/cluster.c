/* cluster.c — the cluster queue of cluster.h: its Lua scripts (enqueue, take, heartbeat,
 * finish, cancel), the origin's calls, and the executor: a take task that turns stream entries
 * into local flights while workers are idle, and a task per taken entry that heart-beats it
 * and reports its end. Tasks run on the Redis tier's thread and enter the scheduler only
 * through their group (ismd_redis_tasks_enter), never holding its lock across a Redis call. */
#include "server/isomeshd/cluster.h"

#include <hiredis/hiredis.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "server/common/cache_redis.h"
#include "server/common/log.h"
#include "server/isomeshd/jobs.h"
#include "server/isomeshd/surface_prefetch.h"

#define KEY_MAX 512
#define TAKE_TICK_NS 25000000LL      /* an idle daemon looks for work this often */
#define TAKE_MAX_PER_TICK 8          /* entries taken in one look at most */
#define CJ_TICK_NS 20000000LL        /* a taken entry's task checks for its flight's end */
#define HEARTBEAT_MAX_NS 500000000LL /* and heart-beats (progress too) at least this often */
#define STATE_TTL_MS "3600000"       /* a job hash outlives its last change by an hour */
#define DEPTH_TICK_NS 1000000000LL   /* the service-wide queue depth is counted this often */
#define DELETES_TICK_NS 100000000LL  /* DELETEs of its jobs through other daemons are looked
                                        for this often: a tenth of a second is quick enough
                                        for a client, and one SPOP each time costs Redis little */
#define DELETES_PER_TICK 64          /* of them, taken at once at most */
#define TEXT_OF(n) #n
#define TEXT(n) TEXT_OF(n)
#define TAKE_TRIES "8"               /* users a take may find with nothing to read (their
                                        P wait entry stale) before it gives up until the next
                                        tick: bounds the script, and each try mends one */
#define NEWEST_SCAN "64"             /* a user's entries taken that a give-back compares
                                        (the first so many: more than any user runs) */
#define TIE_SCAN "64"                /* users tied for the fewest running that a take compares
                                        for the one served longest ago (more than a service
                                        has; past it, a window that moves with the turn) */
#define ORPHAN_CHECK_NS 100000000LL  /* a computation wanted by no request here (its origin's
                                        own, run here) asks this often whether another daemon
                                        waits for it, and stops when none does */

/* ---- scripts ------------------------------------------------------------------------- */

/* Redis's own clock in milliseconds, as text: every daemon's times of a computation (queued,
 * started, ended in its job hash) are read on one clock, in the order Redis ran the scripts. */
#define NOW_MS_LUA \
    "local function now_ms() local t = redis.call('time') " \
    "  return string.format('%.0f', t[1] * 1000 + math.floor(t[2] / 1000)) end "

/* abandoned(p, name, now): a computation whose origin (the daemon that put it on the queue,
 * the job hash's origin) died, and that nothing else wants: no other daemon holds its lock
 * or waits for it (P want:<name>), and every job recorded for it (P cjobs:<name>) was
 * deleted. Nobody is left to let go of it (cluster.h), so a DELETE of its last job, the
 * heartbeat of the daemon running it and a daemon re-claiming it stop it here. p: the key
 * prefix; now: the wall clock in ms (for want). */
#define ABANDONED_LUA \
    "local function abandoned(p, name, now) " \
    "  local jk = p .. 'job:' .. name " \
    "  local o = redis.call('hget', jk, 'origin') " \
    "  if not o or redis.call('exists', p .. 'alive:' .. o) == 1 then return false end " \
    "  local lock = redis.call('get', p .. 'lock:' .. name) " \
    "  if lock and string.sub(lock, 1, #o + 1) ~= o .. '/' then return false end " \
    "  local w = p .. 'want:' .. name " \
    "  redis.call('zremrangebyscore', w, '-inf', now) " \
    "  if redis.call('zcard', w) > 0 then return false end " \
    "  local js = redis.call('smembers', p .. 'cjobs:' .. name) " \
    "  if #js == 0 then return false end " \
    "  for _, id in ipairs(js) do " \
    "    local r = p .. 'jobrec:' .. id " \
    "    if redis.call('exists', r) == 1 and not redis.call('hget', r, 'cancel') then " \
    "      return false end " \
    "  end " \
    "  return true end "

/* A user's state for choosing and sharing, kept beside its streams (P q:<user>, new entries;
 * P r:<user>, entries given back, taken first) so that no script reads every user's:
 *   P run    hash user -> its entries taken (running, or pending on a dead daemon)
 *   P nwait  hash user -> its entries not taken yet
 *   P wait   sorted set: the users with an entry to take and below their running limit,
 *            scored by their entries taken (the fewest first)
 *   P served hash user -> the service's count of takes (P turns) when it last got a worker:
 *            ties in P wait go to the user served longest ago (none yet: first), as one
 *            daemon's fair queue does (job_queue.c's last_turn)
 * refresh(p, u) recomputes u's three from its streams (a handful of commands whatever the
 * number of users) and is called by every script that changes them; streams left with
 * nothing are removed. stream_user(p, s): the user of stream s. */
#define REFRESH_LUA \
    "local function stream_user(p, s) return string.sub(s, #p + 3) end " \
    "local function counts(s) " \
    "  if redis.call('exists', s) == 0 then return 0, 0 end " \
    "  return redis.call('xpending', s, 'workers')[1], redis.call('xlen', s) end " \
    "local function refresh(p, u) " \
    "  local q, r = p .. 'q:' .. u, p .. 'r:' .. u " \
    "  local pq, lq = counts(q) " \
    "  local pr, lr = counts(r) " \
    "  local run, waiting = pq + pr, math.max(lq + lr - pq - pr, 0) " \
    "  if run > 0 then redis.call('hset', p .. 'run', u, run) " \
    "  else redis.call('hdel', p .. 'run', u) end " \
    "  if waiting > 0 then redis.call('hset', p .. 'nwait', u, waiting) " \
    "  else redis.call('hdel', p .. 'nwait', u) end " \
    "  local lim = tonumber(redis.call('hget', p .. 'ulim', u) or '0') or 0 " \
    "  if waiting > 0 and (lim <= 0 or run < lim) then redis.call('zadd', p .. 'wait', run, u) " \
    "  else redis.call('zrem', p .. 'wait', u) end " \
    "  if run == 0 and waiting == 0 then " \
    "    redis.call('del', q, r) redis.call('hdel', p .. 'ulim', u) " \
    "    redis.call('hdel', p .. 'served', u) end end "

/* KEYS stream, job hash, ulim; ARGV user, max entries, name, key, fmt, req, max running,
 * ttl, consumer, key prefix. {entry id, its stream}, or false when the user already has max
 * entries (over its two streams). An entry of the same computation still waiting or running,
 * not canceled (its origin gave it up while other daemons waited for it: CANCEL_LUA), is
 * joined instead of a new one; the daemon joining it (it holds the lock now) becomes its
 * origin. */
static const char ENQUEUE_LUA[] =
    NOW_MS_LUA REFRESH_LUA
    "local cur = redis.call('hget', KEYS[2], 'id') "
    "local st = redis.call('hget', KEYS[2], 'state') "
    "local cs = redis.call('hget', KEYS[2], 'stream') "
    "if cur and cs and (st == 'queued' or st == 'running') "
    "   and not redis.call('hget', KEYS[2], 'cancel') "
    "   and #redis.call('xrange', cs, cur, cur) > 0 then "
    "  redis.call('hset', KEYS[2], 'origin', ARGV[9]) return {cur, cs} end "
    "if redis.call('exists', KEYS[1]) == 0 then "
    "  redis.call('xgroup', 'create', KEYS[1], 'workers', '0', 'MKSTREAM') end "
    "local _, lq = counts(KEYS[1]) "
    "local _, lr = counts(ARGV[10] .. 'r:' .. ARGV[1]) "
    "if lq + lr >= tonumber(ARGV[2]) then return false end "
    "local id = redis.call('xadd', KEYS[1], '*', 'name', ARGV[3], 'key', ARGV[4], "
    "  'fmt', ARGV[5], 'user', ARGV[1], 'req', ARGV[6]) "
    "redis.call('hset', KEYS[3], ARGV[1], ARGV[7]) "
    "redis.call('del', KEYS[2]) "
    "redis.call('hset', KEYS[2], 'state', 'queued', 'progress', '0', 'id', id, "
    "  'stream', KEYS[1], 'origin', ARGV[9], 'queued_ms', now_ms()) "
    "redis.call('pexpire', KEYS[2], ARGV[8]) "
    "refresh(ARGV[10], ARGV[1]) "
    "return {id, KEYS[1]}";

/* KEYS wait, run; ARGV key prefix, consumer, min idle ms, turn, now ms, ttl. {user, stream,
 * id, fields, claimed} or false. Re-claims a dead daemon's entry first (the oldest pending
 * entry idle for a lock lifetime, among the users with entries taken: XPENDING IDLE scans the
 * whole list, where XAUTOCLAIM would look at its first few only; a deleted one is
 * acknowledged, a canceled or abandoned one dropped), else reads a new one from the user with
 * the fewest running, below its limit (P wait's first), of those tied the one served longest
 * ago (P served; before, the turn alone chose, and a user whose computations had all just
 * ended could take the worker ahead of a user waiting with none): its given-back entries
 * first (P r:<user>), then its stream. A user P wait names that has nothing to read
 * leaves it (at most TAKE_TRIES of them per call). */
static const char TAKE_LUA[] =
    NOW_MS_LUA ABANDONED_LUA REFRESH_LUA
    "local p = ARGV[1] "
    "local function name_of(e) "
    "  for i = 1, #e[2], 2 do if e[2][i] == 'name' then return e[2][i + 1] end end "
    "  return nil end "
    "local function start(u, s, e, claimed) "
    "  local name = name_of(e) "
    "  if name then "
    "    local jk = p .. 'job:' .. name "
    "    if redis.call('hget', jk, 'id') == e[1] then "
    "      redis.call('hset', jk, 'state', 'running', 'daemon', ARGV[2], 'started_ms', now_ms()) "
    "      redis.call('pexpire', jk, ARGV[6]) end end "
    "  redis.call('hset', p .. 'served', u, redis.call('incr', p .. 'turns')) "
    "  refresh(p, u) "
    "  return {u, s, e[1], e[2], claimed} end "
    "local function dropped(s, e) "
    "  local name = name_of(e) "
    "  if not name then return false end "
    "  local jk = p .. 'job:' .. name "
    "  if redis.call('hget', jk, 'id') ~= e[1] then return false end "
    "  if not redis.call('hget', jk, 'cancel') and not abandoned(p, name, ARGV[5]) then "
    "    return false end "
    "  redis.call('hset', jk, 'cancel', '1') "
    "  redis.call('xack', s, 'workers', e[1]) redis.call('xdel', s, e[1]) "
    "  return true end "
    "for _, u in ipairs(redis.call('hkeys', KEYS[2])) do "
    "  for _, s in ipairs({p .. 'r:' .. u, p .. 'q:' .. u}) do "
    "    if redis.call('exists', s) == 1 then "
    "      local pe = redis.call('xpending', s, 'workers', 'IDLE', ARGV[3], '-', '+', 1)[1] "
    "      if pe then "
    "        local c = redis.call('xclaim', s, 'workers', ARGV[2], ARGV[3], pe[1]) "
    "        if c[1] and c[1][2] then "
    "          if not dropped(s, c[1]) then return start(u, s, c[1], 1) end "
    "        else redis.call('xack', s, 'workers', pe[1]) end "
    "        refresh(p, u) "
    "      end "
    "    end "
    "  end "
    "end "
    "for try = 1, " TAKE_TRIES " do "
    "  local first = redis.call('zrange', KEYS[1], 0, 0, 'WITHSCORES') "
    "  if #first == 0 then return false end "
    "  local ties = redis.call('zcount', KEYS[1], first[2], first[2]) "
    "  local from = ties > " TIE_SCAN " and tonumber(ARGV[4]) % (ties - " TIE_SCAN " + 1) or 0 "
    "  local tied = redis.call('zrangebyscore', KEYS[1], first[2], first[2], 'LIMIT', from, "
    "    " TIE_SCAN ") "
    "  local last = redis.call('hmget', p .. 'served', unpack(tied)) "
    "  local u, least = nil, nil "
    "  for i, v in ipairs(tied) do "
    "    local n = tonumber(last[i] or '0') or 0 "
    "    if not least or n < least then u, least = v, n end "
    "  end "
    "  for _, s in ipairs({p .. 'r:' .. u, p .. 'q:' .. u}) do "
    "    if redis.call('exists', s) == 1 then "
    "      local r = redis.call('xreadgroup', 'group', 'workers', ARGV[2], 'count', 1, "
    "        'streams', s, '>') "
    "      if r then return start(u, s, r[1][2][1], 0) end "
    "    end "
    "  end "
    "  redis.call('zrem', KEYS[1], u) redis.call('hdel', p .. 'nwait', u) "
    "end "
    "return false";

/* KEYS users; ARGV key prefix. A queue left by daemons older than P run/nwait/wait (their
 * set of users with a stream, P users) gets its users' counts once, from their streams; the
 * set goes. Every daemon runs it as it starts (nothing to do after the first). */
static const char UPGRADE_LUA[] =
    REFRESH_LUA
    "local users = redis.call('smembers', KEYS[1]) "
    "for _, u in ipairs(users) do refresh(ARGV[1], u) end "
    "redis.call('del', KEYS[1]) "
    "return #users";

/* KEYS nwait. Entries waiting (not yet taken) over every user's streams. */
static const char DEPTH_LUA[] =
    "local n = 0 "
    "for _, v in ipairs(redis.call('hvals', KEYS[1])) do n = n + tonumber(v) end "
    "return n";

/* over_share(p, user): the service's fair share, as one daemon's scheduler keeps it
 * (sched.c's preempt victim) but over every daemon: every worker of the service busy (the
 * live daemons' counts, P nworkers), and this user holds two or more while another user
 * with nothing running waits, or (the user's own running limit unset) more than half of the
 * workers, rounded up, while another user holding fewer than half waits. Waiting: an entry
 * not taken yet, below that user's running limit (P wait). Reads P run and the first two of
 * P wait, not every user's streams. */
#define OVER_SHARE_LUA \
    "local function over_share(p, user) " \
    "  local total = 0 " \
    "  local nw = redis.call('hgetall', p .. 'nworkers') " \
    "  for i = 1, #nw, 2 do " \
    "    if redis.call('exists', p .. 'alive:' .. nw[i]) == 1 then " \
    "      total = total + tonumber(nw[i + 1]) " \
    "    else redis.call('hdel', p .. 'nworkers', nw[i]) end " \
    "  end " \
    "  local mine = tonumber(redis.call('hget', p .. 'run', user) or '0') or 0 " \
    "  if total == 0 or mine < 2 then return false end " \
    "  local own = tonumber(redis.call('hget', p .. 'ulim', user) or '0') or 0 " \
    "  local share = own <= 0 and math.ceil(total / 2) or 0 " \
    "  local busy, below = 0, nil " \
    "  for _, v in ipairs(redis.call('hvals', p .. 'run')) do busy = busy + tonumber(v) end " \
    "  if busy < total then return false end " \
    "  local low = redis.call('zrange', p .. 'wait', 0, 1, 'WITHSCORES') " \
    "  for i = 1, #low, 2 do " \
    "    if low[i] ~= user then below = tonumber(low[i + 1]) break end " \
    "  end " \
    "  if below == nil then return false end " \
    "  return below == 0 or (share > 0 and mine > share and below < share) end "

/* newest(p, user, id, started): no other entry of the user taken by a live daemon and able
 * to give back (its job hash's alone, published by its heartbeats) started after this one
 * (id, started_ms started). The entry given back is the newest, as sched.c's preemption takes
 * the one started last: the least work is lost. */
#define NEWEST_LUA \
    "local function newest(p, user, id, started) " \
    "  for _, s in ipairs({p .. 'r:' .. user, p .. 'q:' .. user}) do " \
    "    local taken = {} " \
    "    if redis.call('exists', s) == 1 then " \
    "      taken = redis.call('xpending', s, 'workers', '-', '+', " NEWEST_SCAN ") end " \
    "    for _, x in ipairs(taken) do " \
    "      local e = x[1] ~= id and redis.call('xrange', s, x[1], x[1])[1] " \
    "      for i = 1, e and #e[2] or 0, 2 do " \
    "        if e[2][i] == 'name' then " \
    "          local h = redis.call('hmget', p .. 'job:' .. e[2][i + 1], 'id', 'alone', " \
    "            'started_ms', 'daemon') " \
    "          if h[1] == x[1] and h[2] == '1' and h[4] " \
    "             and tonumber(h[3] or '0') > started " \
    "             and redis.call('exists', p .. 'alive:' .. h[4]) == 1 then return false end " \
    "        end " \
    "      end " \
    "    end " \
    "  end " \
    "  return true end "

/* KEYS stream, job hash; ARGV consumer, id, progress, ttl, key prefix, name, now ms, may
 * give back, user. 1: still ours (idle time reset, progress published); 0: taken over by
 * another daemon, or its record is gone; 2: canceled, or abandoned (ABANDONED_LUA: flagged
 * canceled), both acknowledged and deleted; 3: given back (nothing on this daemon but the
 * entry wants the computation, its user is over the service's share, OVER_SHARE_LUA, and it
 * is the user's newest that may go, NEWEST_LUA): the entry goes to its user's given-back stream (P r:<user>, read before the user's other
 * entries: the user's next computation to start is this one) as a new one, the job hash says
 * queued under its new id (the origin, following the old one, starts over and joins it). */
static const char HEARTBEAT_LUA[] =
    ABANDONED_LUA REFRESH_LUA OVER_SHARE_LUA NEWEST_LUA
    "if redis.call('exists', KEYS[1]) == 0 then return 0 end "
    "local pe = redis.call('xpending', KEYS[1], 'workers', ARGV[2], ARGV[2], 1)[1] "
    "if not pe or pe[2] ~= ARGV[1] then return 0 end "
    "local mine = redis.call('hget', KEYS[2], 'id') == ARGV[2] "
    "if mine and not redis.call('hget', KEYS[2], 'cancel') "
    "   and abandoned(ARGV[5], ARGV[6], ARGV[7]) then "
    "  redis.call('hset', KEYS[2], 'cancel', '1') end "
    "local e = redis.call('xrange', KEYS[1], ARGV[2], ARGV[2])[1] "
    "if not e or not mine or redis.call('hget', KEYS[2], 'cancel') then "
    "  redis.call('xack', KEYS[1], 'workers', ARGV[2]) redis.call('xdel', KEYS[1], ARGV[2]) "
    "  refresh(ARGV[5], ARGV[9]) "
    "  if mine and e then return 2 end return 0 end "
    "if ARGV[8] == '1' and over_share(ARGV[5], ARGV[9]) and newest(ARGV[5], ARGV[9], ARGV[2], "
    "   tonumber(redis.call('hget', KEYS[2], 'started_ms') or '0')) then "
    "  redis.call('xack', KEYS[1], 'workers', ARGV[2]) redis.call('xdel', KEYS[1], ARGV[2]) "
    "  local r = ARGV[5] .. 'r:' .. ARGV[9] "
    "  if redis.call('exists', r) == 0 then "
    "    redis.call('xgroup', 'create', r, 'workers', '0', 'MKSTREAM') end "
    "  local id = redis.call('xadd', r, '*', unpack(e[2])) "
    "  redis.call('hset', KEYS[2], 'id', id, 'stream', r, 'state', 'queued', 'progress', '0') "
    "  redis.call('hdel', KEYS[2], 'daemon', 'started_ms') "
    "  refresh(ARGV[5], ARGV[9]) "
    "  return 3 end "
    "redis.call('xclaim', KEYS[1], 'workers', ARGV[1], 0, ARGV[2], 'JUSTID') "
    "redis.call('hset', KEYS[2], 'progress', ARGV[3], 'alone', ARGV[8]) "
    "redis.call('pexpire', KEYS[2], ARGV[4]) "
    "return 1";

/* KEYS alive, nworkers; ARGV ttl, consumer, workers. This daemon lives for one more lock
 * lifetime, with its worker count (the service's share counts live daemons' workers). */
static const char ALIVE_LUA[] =
    "redis.call('set', KEYS[1], '1', 'PX', ARGV[1]) "
    "redis.call('hset', KEYS[2], ARGV[2], ARGV[3]) "
    "return 1";

/* KEYS stream, job hash; ARGV id, state, status, error, ttl, key prefix. */
static const char FINISH_LUA[] =
    NOW_MS_LUA REFRESH_LUA
    "redis.call('xack', KEYS[1], 'workers', ARGV[1]) "
    "redis.call('xdel', KEYS[1], ARGV[1]) "
    "if redis.call('hget', KEYS[2], 'id') == ARGV[1] then "
    "  redis.call('hset', KEYS[2], 'state', ARGV[2], 'status', ARGV[3], 'error', ARGV[4], "
    "    'progress', '1', 'ended_ms', now_ms()) "
    "  redis.call('pexpire', KEYS[2], ARGV[5]) end "
    "refresh(ARGV[6], stream_user(ARGV[6], KEYS[1])) "
    "return 1";

/* KEYS jobrec; ARGV key prefix, job id, ttl, now ms. DELETE of a job through a daemon that
 * does not hold it: the job's record says canceled (the job's own flag: its computation may
 * be shared), and its id goes to the set of the daemon holding it, which lets go of that job
 * as a DELETE there would (and takes the flag back when the job had finished first:
 * UNDELETE_LUA). The flag is 'final' when that daemon is not alive: it cannot have finished
 * the job first as far as the cluster knows, the client is told canceled and the
 * computation may be stopped as abandoned, so the job stays canceled even if a computation
 * started over for other requests there finishes it before it takes the set (seen at load
 * 20: test_a_daemon_cut_off_past_the_lock_lifetime_keeps_its_requests_computation read done
 * after the DELETE answered canceled). A live daemon takes the set within DELETES_TICK_NS,
 * so its flag stays '1'. A dead daemon lets go of nothing: when the job was the last thing
 * anyone wanted of its
 * computation (ABANDONED_LUA), the computation is flagged canceled here, a waiting entry
 * deleted, a running one stopped by its executor's next heartbeat, a pending one dropped by
 * the daemon re-claiming it. 0 when no daemon recorded the job, 2 when its computation was
 * stopped that way, else 1. */
static const char JOB_DELETE_LUA[] =
    ABANDONED_LUA REFRESH_LUA
    "local d = redis.call('hget', KEYS[1], 'daemon') "
    "if not d then return 0 end "
    "if redis.call('hget', KEYS[1], 'cancel') ~= 'final' then "
    "  redis.call('hset', KEYS[1], 'cancel', "
    "    redis.call('exists', ARGV[1] .. 'alive:' .. d) == 1 and '1' or 'final') end "
    "local s = ARGV[1] .. 'deleted:' .. d "
    "redis.call('sadd', s, ARGV[2]) "
    "redis.call('pexpire', s, ARGV[3]) "
    "local key = redis.call('hget', KEYS[1], 'key') "
    "local fmt = redis.call('hget', KEYS[1], 'fmt') "
    "if not key or not fmt then return 1 end "
    "local name = key .. '.' .. fmt "
    "local jk = ARGV[1] .. 'job:' .. name "
    "local id = redis.call('hget', jk, 'id') "
    "local st = redis.call('hget', jk, 'state') "
    "local cs = redis.call('hget', jk, 'stream') "
    "if not id or not cs or (st ~= 'queued' and st ~= 'running') "
    "   or redis.call('hget', jk, 'cancel') or not abandoned(ARGV[1], name, ARGV[4]) then "
    "  return 1 end "
    "redis.call('hset', jk, 'cancel', '1') "
    "if redis.call('exists', cs) == 1 "
    "   and not redis.call('xpending', cs, 'workers', id, id, 1)[1] then "
    "  redis.call('xdel', cs, id) refresh(ARGV[1], stream_user(ARGV[1], cs)) end "
    "return 2";

/* KEYS jobrec. A job deleted through another daemon (JOB_DELETE_LUA) had finished here
 * first: its record says its end rather than canceled, unless the DELETE found this daemon
 * dead (the flag is 'final'). 1 when the flag was taken back, 0 when it stays. */
static const char UNDELETE_LUA[] =
    "if redis.call('hget', KEYS[1], 'cancel') == 'final' then return 0 end "
    "redis.call('hdel', KEYS[1], 'cancel') "
    "return 1";

/* KEYS stream, job hash; ARGV id, key prefix. The executor's flight was canceled here
 * (nobody waits for it any more): the entry goes, its job hash says canceled. */
static const char DROPPED_LUA[] =
    REFRESH_LUA
    "redis.call('xack', KEYS[1], 'workers', ARGV[1]) "
    "redis.call('xdel', KEYS[1], ARGV[1]) "
    "if redis.call('hget', KEYS[2], 'id') == ARGV[1] then "
    "  redis.call('hset', KEYS[2], 'cancel', '1') end "
    "refresh(ARGV[2], stream_user(ARGV[2], KEYS[1])) "
    "return 1";

/* KEYS cjobs; ARGV job id, ttl. */
static const char CJOBS_ADD_LUA[] =
    "redis.call('sadd', KEYS[1], ARGV[1]) "
    "redis.call('pexpire', KEYS[1], ARGV[2]) "
    "return 1";

/* The daemons other than ARGV[self] that want KEYS[want] now (ARGV[now] in ms): expired
 * wishes are dropped first. A Lua fragment defining n. */
#define WANTED_LUA(want, now, self) \
    "redis.call('zremrangebyscore', KEYS[" want "], '-inf', ARGV[" now "]) " \
    "local n = redis.call('zcard', KEYS[" want "]) " \
    "if redis.call('zscore', KEYS[" want "], ARGV[" self "]) then n = n - 1 end "

/* KEYS want; ARGV now ms, consumer. How many other daemons wait for the computation. */
static const char WANTED_ELSEWHERE_LUA[] = WANTED_LUA("1", "1", "2") "return n";

/* KEYS want; ARGV consumer, until ms, key ttl ms. This daemon waits for the computation. */
static const char WANT_LUA[] =
    "redis.call('zadd', KEYS[1], ARGV[2], ARGV[1]) "
    "redis.call('pexpire', KEYS[1], ARGV[3]) "
    "return 1";

/* KEYS stream, job hash, want; ARGV id, now ms, consumer, key prefix. The origin has
 * nobody waiting any more: unless another daemon waits for the computation (then it goes on,
 * and the first of them to take its lock joins the entry: ENQUEUE_LUA), a waiting entry goes,
 * a running one is flagged. */
static const char CANCEL_LUA[] =
    WANTED_LUA("3", "2", "3") REFRESH_LUA
    "local mine = redis.call('hget', KEYS[2], 'id') == ARGV[1] "
    "if mine and n > 0 then return 0 end "
    "if mine then redis.call('hset', KEYS[2], 'cancel', '1') end "
    "if redis.call('exists', KEYS[1]) == 1 "
    "   and not redis.call('xpending', KEYS[1], 'workers', ARGV[1], ARGV[1], 1)[1] then "
    "  redis.call('xdel', KEYS[1], ARGV[1]) refresh(ARGV[4], stream_user(ARGV[4], KEYS[1])) end "
    "return 1";

struct ismd_cluster {
    ismd_redis_tasks *tasks;   /* this queue's tasks, with the shared stage's */
    ismd_sched *sched;
    ism_cache *cache;
    ism_cache_tier *redis;
    const ism_pipeline_limits *limits;
    char consumer[128];        /* this daemon in the consumer group */
    long ttl_ms;               /* a silent daemon's entries are re-claimed after this */
    int user_jobs, user_running;
    unsigned long turn;        /* rotates the order among users with equal load */
    long long depth_at_ns;     /* when to count the service-wide queue next */
    long long alive_at_ns;     /* when to say next that this daemon lives (P alive:<it>) */
    ismd_jobs *jobs;           /* this daemon's jobs (DELETEs through other daemons) */
    long long deletes_at_ns;   /* when to look for those next */
    bool upgraded;             /* UPGRADE_LUA has run */
    ism_redis_task take;
};

/* One taken entry: the local flight's waiter and the task that heart-beats it. */
typedef struct cjob {
    ism_redis_task base;       /* first: the tier hands this back */
    ismd_waiter waiter;
    ismd_cluster *c;
    char stream[KEY_MAX], job[KEY_MAX], name[ISM_CACHE_NAME_MAX];
    char id[ISMD_CLUSTER_ID_MAX];
    char user[ISMD_CLUSTER_KEY_MAX];
    long long beat_at_ns, orphan_check_ns;
    bool kept_logged;          /* cluster_computation_kept said for it */
    /* set under the scheduler's lock by the flight */
    bool finished;
    unsigned status;
    ism_blob *error;
    double progress;
} cjob;

static int run_script(ismd_cluster *c, const char *what, const char *lua, int nkeys,
                      const char **args, int nargs, redisReply **out)
{
    const char *argv[24] = {"EVAL", lua, NULL};
    size_t lens[24] = {4, strlen(lua), 0};
    char nk[8];
    snprintf(nk, sizeof nk, "%d", nkeys);
    argv[2] = nk;
    lens[2] = strlen(nk);
    for (int i = 0; i < nargs && i < 21; i++) {
        argv[3 + i] = args[i];
        lens[3 + i] = strlen(args[i]);
    }
    redisReply *r = ism_cache_redis_call(c->redis, what, 3 + nargs, argv, lens);
    if (!r)
        return -1;
    if (out)
        *out = r;
    else
        freeReplyObject(r);
    return 0;
}

/* How often a daemon says in Redis that it lives, or runs an entry: three times a lock
 * lifetime, and at least every HEARTBEAT_MAX_NS. */
static long long beat_every_ns(const ismd_cluster *c)
{
    long long every = c->ttl_ms * 1000000LL / 3;
    return every < HEARTBEAT_MAX_NS ? every : HEARTBEAT_MAX_NS;
}

/* "<namespace>:v1:<kind><name>" (kind "job:", "q:", "users", ...). */
static void ckey(const ismd_cluster *c, char out[KEY_MAX], const char *kind, const char *name)
{
    snprintf(out, KEY_MAX, "%s%s%s", ism_cache_redis_prefix(c->redis), kind, name);
}

static const char *reply_str(const redisReply *e)
{
    return e && e->type == REDIS_REPLY_STRING ? e->str : NULL;
}

/* The wall clock in milliseconds, as text, plus ahead_ms. */
static void wall_ms(char out[24], long long ahead_ms)
{
    struct timespec wall;
    clock_gettime(CLOCK_REALTIME, &wall);
    snprintf(out, 24, "%lld", (long long)wall.tv_sec * 1000 + wall.tv_nsec / 1000000 + ahead_ms);
}

/* A computation nobody here waits for goes on for another daemon's requests (who: the
 * origin deciding on its own, or its executor here). */
static void log_kept(const char *name, const char *who)
{
    ism_log_field f[] = {ISM_LS("name", name), ISM_LS("by", who)};
    ism_log_fields(ISM_LOG_INFO, "cluster_computation_kept", f, 2);
}

/* ---- the origin ---------------------------------------------------------------------- */

int ismd_cluster_enqueue(ismd_cluster *c, const char *name, const char *key, const char *fmt,
                         const char *user, const ismd_user_limits *lim, const ism_blob *request,
                         char id[ISMD_CLUSTER_ID_MAX], char stream_out[ISMD_CLUSTER_KEY_MAX])
{
    char stream[KEY_MAX], job[KEY_MAX], jobs[16], running[16];
    char *req = malloc(request->len + 1);
    if (!req)
        return -1;
    memcpy(req, request->data, request->len);
    req[request->len] = 0;
    ckey(c, stream, "q:", user);
    ckey(c, job, "job:", name);
    snprintf(jobs, sizeof jobs, "%d", lim && lim->max_jobs > 0 ? lim->max_jobs : c->user_jobs);
    snprintf(running, sizeof running, "%d",
             lim && lim->max_running > 0 ? lim->max_running : c->user_running);
    char ulim[KEY_MAX];
    ckey(c, ulim, "ulim", "");
    const char *args[] = {stream, job, ulim, user, jobs, name, key, fmt, req,
                          running, STATE_TTL_MS, c->consumer, ism_cache_redis_prefix(c->redis)};
    redisReply *r = NULL;
    int rc = run_script(c, "cluster_enqueue", ENQUEUE_LUA, 3, args, 13, &r);
    free(req);
    if (rc < 0)
        return -1;
    int got = r->type == REDIS_REPLY_NIL ? 0 : -1;
    if (r->type == REDIS_REPLY_ARRAY && r->elements == 2 && reply_str(r->element[0]) &&
        reply_str(r->element[1])) {
        snprintf(id, ISMD_CLUSTER_ID_MAX, "%s", r->element[0]->str);
        snprintf(stream_out, ISMD_CLUSTER_KEY_MAX, "%s", r->element[1]->str);
        got = 1;
    }
    freeReplyObject(r);
    return got;
}

int ismd_cluster_view(ismd_cluster *c, const char *name, const char *id, ismd_cj_view *v)
{
    char job[KEY_MAX];
    ckey(c, job, "job:", name);
    memset(v, 0, sizeof *v);
    const char *argv[] = {"HMGET", job, "id", "state", "progress", "status", "error", "cancel"};
    size_t lens[8];
    for (int i = 0; i < 8; i++)
        lens[i] = strlen(argv[i]);
    redisReply *r = ism_cache_redis_call(c->redis, "cluster_view", 8, argv, lens);
    if (!r)
        return -1;
    if (r->type != REDIS_REPLY_ARRAY || r->elements != 6) {
        freeReplyObject(r);
        return -1;
    }
    const char *got_id = reply_str(r->element[0]), *state = reply_str(r->element[1]);
    if (got_id && state && !strcmp(got_id, id)) {
        v->state = !strcmp(state, "queued")    ? ISMD_CJ_QUEUED
                   : !strcmp(state, "running") ? ISMD_CJ_RUNNING
                   : !strcmp(state, "done")    ? ISMD_CJ_DONE
                                               : ISMD_CJ_FAILED;
        const char *p = reply_str(r->element[2]), *st = reply_str(r->element[3]);
        const char *err = reply_str(r->element[4]);
        v->progress = p ? strtod(p, NULL) : 0;
        v->status = st ? (unsigned)strtoul(st, NULL, 10) : 500;
        if (v->state == ISMD_CJ_FAILED && err)
            v->error = ism_blob_from_str(err);
        if (v->state < ISMD_CJ_DONE && reply_str(r->element[5]))
            v->state = ISMD_CJ_CANCELED; /* its origin gave it up (cluster.h) */
    }
    freeReplyObject(r);
    return 0;
}

bool ismd_cluster_cancel(ismd_cluster *c, const char *name, const char *stream, const char *id)
{
    char job[KEY_MAX], want[KEY_MAX], now[24];
    ckey(c, job, "job:", name);
    ckey(c, want, "want:", name);
    wall_ms(now, 0);
    const char *args[] = {stream, job, want, id, now, c->consumer,
                          ism_cache_redis_prefix(c->redis)};
    redisReply *r = NULL;
    if (run_script(c, "cluster_cancel", CANCEL_LUA, 3, args, 7, &r) < 0)
        return false;
    if (r->type == REDIS_REPLY_INTEGER && r->integer == 0)
        log_kept(name, "origin");
    freeReplyObject(r);
    return true;
}

void ismd_cluster_want(ismd_cluster *c, const char *name, bool want)
{
    char key[KEY_MAX], until[24], ttl[24];
    ckey(c, key, "want:", name);
    if (!want) {
        const char *argv[] = {"ZREM", key, c->consumer};
        size_t lens[] = {4, strlen(key), strlen(c->consumer)};
        redisReply *r = ism_cache_redis_call(c->redis, "cluster_unwant", 3, argv, lens);
        if (r)
            freeReplyObject(r);
        return;
    }
    wall_ms(until, c->ttl_ms);
    snprintf(ttl, sizeof ttl, "%ld", 2 * c->ttl_ms);
    const char *args[] = {key, c->consumer, until, ttl};
    run_script(c, "cluster_want", WANT_LUA, 1, args, 4, NULL);
}

/* Whether another daemon waits for name now (false when Redis does not say). */
static bool wanted_elsewhere(ismd_cluster *c, const char *name)
{
    char key[KEY_MAX], now[24];
    ckey(c, key, "want:", name);
    wall_ms(now, 0);
    const char *args[] = {key, now, c->consumer};
    redisReply *r = NULL;
    if (run_script(c, "cluster_wanted", WANTED_ELSEWHERE_LUA, 1, args, 3, &r) < 0)
        return false;
    bool wanted = r->type == REDIS_REPLY_INTEGER && r->integer > 0;
    freeReplyObject(r);
    return wanted;
}

/* ---- a taken entry ------------------------------------------------------------------- */

static void cj_done(ismd_waiter *w, const ismd_result *r)
{
    cjob *j = (cjob *)((char *)w - offsetof(cjob, waiter));
    j->finished = true;
    j->status = r->status;
    if (r->status != 200)
        ism_blob_set(&j->error, r->body);
}

static void cj_progress(ismd_waiter *w, double fraction, bool running)
{
    (void)running;
    cjob *j = (cjob *)((char *)w - offsetof(cjob, waiter));
    j->progress = fraction;
}

static long long cj_end(cjob *j)
{
    ismd_redis_tasks *g = j->c->tasks;
    ism_blob_unref(j->error);
    free(j);
    ismd_redis_tasks_ended(g);
    return 0;
}

/* The flight ended: its results are in Redis before the job hash says so. A refusal by this
 * daemon (shutting down, queue full) is not the computation's answer: the entry is left
 * pending, and another daemon re-claims it one lock lifetime later. A cancel (499: nobody
 * waits any more) drops the entry and marks the hash canceled. */
static void cj_report(cjob *j, ism_cache_tier *t)
{
    if (j->status == 503 || j->status == 429)
        return;
    if (j->status == 499) {
        const char *args[] = {j->stream, j->job, j->id, ism_cache_redis_prefix(j->c->redis)};
        run_script(j->c, "cluster_dropped", DROPPED_LUA, 2, args, 4, NULL);
        return;
    }
    ism_cache_redis_flush(t);
    char status[16];
    snprintf(status, sizeof status, "%u", j->status);
    char *err = NULL;
    if (j->error) {
        err = malloc(j->error->len + 1);
        if (err) {
            memcpy(err, j->error->data, j->error->len);
            err[j->error->len] = 0;
        }
    }
    const char *args[] = {j->stream, j->job, j->id, j->status == 200 ? "done" : "failed",
                          status, err ? err : "", STATE_TTL_MS,
                          ism_cache_redis_prefix(j->c->redis)};
    run_script(j->c, "cluster_finish", FINISH_LUA, 2, args, 8, NULL);
    free(err);
}

/* Still ours and wanted: 1; taken over: 0; canceled: 2; given back: 3; Redis unavailable:
 * -1. */
static int cj_beat(cjob *j, double progress, bool may_give_back)
{
    char p[32];
    snprintf(p, sizeof p, "%.4f", progress);
    char now[24];
    wall_ms(now, 0);
    const char *args[] = {j->stream, j->job, j->c->consumer, j->id, p, STATE_TTL_MS,
                          ism_cache_redis_prefix(j->c->redis), j->name, now,
                          may_give_back ? "1" : "0", j->user};
    redisReply *r = NULL;
    if (run_script(j->c, "cluster_heartbeat", HEARTBEAT_LUA, 2, args, 11, &r) < 0)
        return -1;
    int v = r->type == REDIS_REPLY_INTEGER ? (int)r->integer : -1;
    freeReplyObject(r);
    return v;
}

/* Nobody here waits for the origin's own flight any more, nor does another daemon: it stops
 * (its waiter, this task's, is answered 499 and drops the entry). */
static void cancel_orphan(cjob *j)
{
    if (!ismd_redis_tasks_enter(j->c->tasks))
        return;
    ismd_flight *f = j->waiter.flight;
    if (f && ismd_sched_only_passive(f))
        ismd_sched_cancel(j->c->sched, f);
    ismd_redis_tasks_leave(j->c->tasks);
}

static long long cj_run(ism_redis_task *base, ism_cache_tier *t, bool stopping)
{
    cjob *j = (cjob *)base;
    ismd_redis_tasks *g = j->c->tasks;
    if (stopping || !ismd_redis_tasks_enter(g)) {
        /* the pool has stopped: the flight is over. Left pending for another daemon. */
        if (j->finished)
            return cj_end(j);
        ismd_redis_tasks_ended(g); /* still a waiter of a flight: leaked, never freed twice */
        return 0;
    }
    /* finished, but its entries still wait for its surface (sched.h storing): reported once
     * they are in Redis, where its origin then reads them */
    bool finished = j->finished && !ismd_sched_storing(j->c->sched, j->name);
    double progress = j->progress;
    bool orphan = !finished && j->waiter.passive && j->waiter.flight &&
                  ismd_sched_only_passive(j->waiter.flight);
    /* only an entry that nothing else here wants gives its worker back */
    bool alone = !finished && !j->waiter.passive && j->waiter.flight &&
                 j->waiter.flight->nwaiters == 1;
    ismd_redis_tasks_leave(g);
    if (finished) {
        cj_report(j, t);
        return cj_end(j);
    }
    long long now = ism_now_ns();
    if (orphan && now >= j->orphan_check_ns) {
        j->orphan_check_ns = now + ORPHAN_CHECK_NS;
        if (!wanted_elsewhere(j->c, j->name))
            cancel_orphan(j);
        else if (!j->kept_logged) {
            j->kept_logged = true;
            log_kept(j->name, "executor");
        }
    }
    if (now < j->beat_at_ns)
        return now + CJ_TICK_NS;
    j->beat_at_ns = now + beat_every_ns(j->c);
    int beat = cj_beat(j, progress, alone);
    if (beat == 1 || beat < 0)
        return now + CJ_TICK_NS;
    if (beat == 3) {
        ism_log_field lf[] = {ISM_LS("job", j->name), ISM_LS("user", j->user)};
        ism_log_fields(ISM_LOG_INFO, "cluster_computation_preempted", lf, 2);
        atomic_fetch_add(&j->c->sched->metrics->preemptions, 1);
    }
    if (!ismd_redis_tasks_enter(g))
        return now + CJ_TICK_NS;
    /* canceled by its origin (nobody there wants it any more), or taken over by another
     * daemon: stop computing it here unless requests here wait for it too (they keep it, as
     * a local cancel would; so does the origin's own flight when it runs here) */
    if (!j->finished)
        ismd_sched_detach(j->c->sched, &j->waiter);
    ismd_redis_tasks_leave(g);
    ism_log_field f[] = {ISM_LS("job", j->name), ISM_LS("entry", j->id)};
    ism_log_fields(ISM_LOG_INFO, "cluster_job_dropped", f, 2);
    return cj_end(j);
}

/* ---- taking entries ------------------------------------------------------------------ */

static const char *field(const redisReply *fields, const char *name)
{
    for (size_t i = 0; i + 1 < fields->elements; i += 2)
        if (reply_str(fields->element[i]) && !strcmp(fields->element[i]->str, name))
            return reply_str(fields->element[i + 1]);
    return NULL;
}

/* Workers that would start a flight now. Scheduler lock held. */
static long long idle_capacity(const ismd_sched *s)
{
    const ismd_metrics *m = s->metrics;
    return atomic_load(&m->workers_ready) - atomic_load(&m->workers_busy) -
           (long long)s->queue->ops->length(s->queue);
}

/* Makes a taken entry a local flight. False when it could not (left pending). */
static bool start_entry(ismd_cluster *c, const redisReply *r)
{
    const redisReply *fields = r->element[3];
    const char *stream = reply_str(r->element[1]), *id = reply_str(r->element[2]);
    const char *name = field(fields, "name"), *key = field(fields, "key");
    const char *fmt = field(fields, "fmt"), *user = field(fields, "user");
    const char *req = field(fields, "req");
    if (!stream || !id || !name || !key || !fmt || !user || !req)
        return false;
    cjob *j = calloc(1, sizeof *j);
    ism_blob *request = ism_blob_from_str(req);
    if (!j || !request || !ismd_redis_tasks_added(c->tasks)) {
        free(j);
        ism_blob_unref(request);
        return false;
    }
    j->c = c;
    j->base.run = cj_run;
    j->waiter.done = cj_done;
    j->waiter.progress = cj_progress;
    snprintf(j->stream, sizeof j->stream, "%s", stream);
    ckey(c, j->job, "job:", name);
    snprintf(j->name, sizeof j->name, "%s", name);
    snprintf(j->id, sizeof j->id, "%s", id);
    snprintf(j->user, sizeof j->user, "%s", user);
    ismd_prefetch_surface(c->cache, c->redis, c->limits, request, NULL, true); /* encode */
    bool ok = false;
    if (ismd_redis_tasks_enter(c->tasks)) {
        ismd_submit st = ismd_sched_submit_here(c->sched, key, fmt, request, user, NULL,
                                                &j->waiter);
        ok = st == ISMD_SUBMIT_NEW || st == ISMD_SUBMIT_JOINED;
        /* its own origin's flight: the entry stands for the waiters already here */
        j->waiter.passive = ok && !strcmp(j->waiter.flight->cluster_entry, id);
        if (ok)
            atomic_fetch_add(r->element[4]->integer ? &c->sched->metrics->cluster_reclaimed
                                                    : &c->sched->metrics->cluster_taken, 1);
        ismd_redis_tasks_leave(c->tasks);
    }
    ism_blob_unref(request);
    if (!ok) {
        cj_end(j);
        return false;
    }
    if (r->element[4]->integer) {
        ism_log_field f[] = {ISM_LS("job", name), ISM_LS("entry", id), ISM_LS("user", user)};
        ism_log_fields(ISM_LOG_WARN, "cluster_job_reclaimed", f, 3);
    }
    ism_cache_redis_schedule(c->redis, &j->base, 0);
    return true;
}

/* One entry for this daemon: 1 taken, 0 none, -1 Redis unavailable. */
static int take_one(ismd_cluster *c)
{
    char idle_ms[24], turn[24], now_ms[24];
    snprintf(idle_ms, sizeof idle_ms, "%ld", c->ttl_ms);
    snprintf(turn, sizeof turn, "%lu", c->turn++);
    wall_ms(now_ms, 0);
    char wait[KEY_MAX], run[KEY_MAX];
    ckey(c, wait, "wait", "");
    ckey(c, run, "run", "");
    const char *args[] = {wait, run, ism_cache_redis_prefix(c->redis), c->consumer, idle_ms,
                          turn, now_ms, STATE_TTL_MS};
    redisReply *r = NULL;
    if (run_script(c, "cluster_take", TAKE_LUA, 2, args, 8, &r) < 0)
        return -1;
    int got = 0;
    if (r->type == REDIS_REPLY_ARRAY && r->elements == 5 &&
        r->element[3]->type == REDIS_REPLY_ARRAY && r->element[4]->type == REDIS_REPLY_INTEGER)
        got = start_entry(c, r) ? 1 : 0;
    freeReplyObject(r);
    return got;
}

/* Publishes how many entries wait in the whole service (isomesh_cluster_queue_depth). */
static void count_waiting(ismd_cluster *c)
{
    char nwait[KEY_MAX];
    ckey(c, nwait, "nwait", "");
    const char *args[] = {nwait};
    redisReply *r = NULL;
    if (run_script(c, "cluster_depth", DEPTH_LUA, 1, args, 1, &r) < 0)
        return;
    if (r->type == REDIS_REPLY_INTEGER)
        atomic_store(&c->sched->metrics->cluster_queue_depth, r->integer);
    freeReplyObject(r);
}

/* A job deleted through another daemon had finished first (or is forgotten): its record
 * says what this daemon says, its end rather than canceled (UNDELETE_LUA). 1 taken back, 0
 * the DELETE found this daemon dead (the job stays canceled), -1 Redis unavailable. */
static int undelete(ismd_cluster *c, const char *id)
{
    char rec[KEY_MAX];
    ckey(c, rec, "jobrec:", id);
    const char *args[] = {rec};
    redisReply *r = NULL;
    if (run_script(c, "jobrec_undelete", UNDELETE_LUA, 1, args, 1, &r) < 0)
        return -1;
    int back = r->type == REDIS_REPLY_INTEGER && r->integer == 0 ? 0 : 1;
    freeReplyObject(r);
    return back;
}

/* Lets go of the jobs here that were deleted through other daemons (JOB_DELETE_LUA), each
 * as a DELETE here would: the job is canceled, its computation stops only when nothing else
 * here waits for it. The ids are read (SRANDMEMBER) and removed only once handled (SREM):
 * a SPOP whose answer came later than the command timeout (ISM_REDIS_COMMAND_TIMEOUT_MS, on
 * a loaded machine) had taken them from Redis for nobody, and those jobs were never let go
 * of (seen in a CI run: redis_unavailable what=cluster_deletes). Handling an id twice (its
 * SREM lost the same way, or a retried DELETE) changes nothing: a job canceled here keeps
 * its record's flag. */
static void take_deletes(ismd_cluster *c)
{
    char set[KEY_MAX];
    ckey(c, set, "deleted:", c->consumer);
    const char *argv[] = {"SRANDMEMBER", set, TEXT(DELETES_PER_TICK)};
    size_t lens[] = {11, strlen(set), strlen(TEXT(DELETES_PER_TICK))};
    redisReply *r = ism_cache_redis_call(c->redis, "cluster_deletes", 3, argv, lens);
    if (!r)
        return;
    const char *done[2 + DELETES_PER_TICK] = {"SREM", set};
    size_t done_lens[2 + DELETES_PER_TICK] = {4, strlen(set)};
    int ndone = 2;
    for (size_t i = 0; r->type == REDIS_REPLY_ARRAY && i < r->elements && i < DELETES_PER_TICK;
         i++) {
        const char *id = reply_str(r->element[i]);
        if (!id || !ismd_redis_tasks_enter(c->tasks))
            continue; /* stays in the set: the next tick */
        ismd_job *job = ismd_jobs_find(c->jobs, id);
        bool live = job && ismd_jobs_cancel(c->jobs, c->sched, job);
        bool canceled = job && !live && ismd_job_canceled(job);
        ismd_redis_tasks_leave(c->tasks);
        bool revoked = false;
        int back = live || canceled ? 1 : undelete(c, id);
        if (back < 0)
            continue; /* Redis did not answer: the next tick */
        if (back == 0 && job && ismd_redis_tasks_enter(c->tasks)) {
            /* found dead when deleted: the job reads canceled here as everywhere (looked
             * up again: the table may have dropped it while the lock was not held) */
            if ((job = ismd_jobs_find(c->jobs, id))) {
                ismd_jobs_revoke(c->jobs, job);
                revoked = true;
            }
            ismd_redis_tasks_leave(c->tasks);
        }
        done[ndone] = id;
        done_lens[ndone++] = strlen(id);
        ism_log_field f[] = {ISM_LS("job", id),
                             ISM_LS("was", live       ? "live"
                                           : canceled ? "canceled"
                                           : revoked  ? "finished_after_the_delete"
                                           : job      ? "finished"
                                                      : "unknown")};
        ism_log_fields(ISM_LOG_INFO, "cluster_job_deleted", f, 2);
    }
    redisReply *gone = ndone > 2 ? ism_cache_redis_call(c->redis, "cluster_deletes_taken",
                                                        ndone, done, done_lens)
                                 : NULL;
    if (gone) /* else lost: those ids are handled again (no change) next tick */
        freeReplyObject(gone);
    freeReplyObject(r);
}

/* P alive:<this daemon> for one lock lifetime: a daemon without it has died (or stopped), and
 * nobody lets go of its jobs any more (ABANDONED_LUA). */
static void say_alive(ismd_cluster *c)
{
    char key[KEY_MAX], counts[KEY_MAX], ttl[24], workers[24];
    ckey(c, key, "alive:", c->consumer);
    ckey(c, counts, "nworkers", "");
    snprintf(ttl, sizeof ttl, "%ld", c->ttl_ms);
    snprintf(workers, sizeof workers, "%lld",
             (long long)atomic_load(&c->sched->metrics->workers_total));
    const char *args[] = {key, counts, ttl, c->consumer, workers};
    run_script(c, "cluster_alive", ALIVE_LUA, 2, args, 5, NULL);
}

/* UPGRADE_LUA; true once it ran. */
static bool upgrade(ismd_cluster *c)
{
    char users[KEY_MAX];
    ckey(c, users, "users", "");
    const char *args[] = {users, ism_cache_redis_prefix(c->redis)};
    redisReply *r = NULL;
    if (run_script(c, "cluster_upgrade", UPGRADE_LUA, 1, args, 2, &r) < 0)
        return false;
    bool ran = r->type == REDIS_REPLY_INTEGER;
    if (ran && r->integer > 0) {
        char n[24];
        snprintf(n, sizeof n, "%lld", (long long)r->integer);
        ism_log_field f = ISM_LS("users", n);
        ism_log_fields(ISM_LOG_INFO, "cluster_queue_upgraded", &f, 1);
    }
    freeReplyObject(r);
    return ran;
}

static long long take_run(ism_redis_task *base, ism_cache_tier *t, bool stopping)
{
    ismd_cluster *c = (ismd_cluster *)((char *)base - offsetof(ismd_cluster, take));
    if (stopping || !ismd_redis_tasks_enter(c->tasks)) {
        ismd_redis_tasks_ended(c->tasks);
        return 0; /* c is freed with the stage */
    }
    long long idle = idle_capacity(c->sched);
    bool draining = c->sched->draining;
    ismd_redis_tasks_leave(c->tasks);
    if (!c->upgraded && ism_cache_redis_up(t))
        c->upgraded = upgrade(c);
    for (long long i = 0; !draining && ism_cache_redis_up(t) && i < idle && i < TAKE_MAX_PER_TICK;
         i++)
        if (take_one(c) <= 0)
            break;
    long long now = ism_now_ns();
    if (now >= c->alive_at_ns && ism_cache_redis_up(t)) {
        c->alive_at_ns = now + beat_every_ns(c);
        say_alive(c);
    }
    if (now >= c->depth_at_ns && ism_cache_redis_up(t)) {
        c->depth_at_ns = now + DEPTH_TICK_NS;
        count_waiting(c);
    }
    if (now >= c->deletes_at_ns && ism_cache_redis_up(t)) {
        c->deletes_at_ns = now + DELETES_TICK_NS;
        take_deletes(c);
    }
    return now + TAKE_TICK_NS;
}

ismd_cluster *ismd_cluster_start(const ismd_cluster_env *env, const ismd_cluster_settings *set)
{
    ismd_cluster *c = calloc(1, sizeof *c);
    if (!c)
        return NULL;
    c->tasks = env->tasks;
    c->sched = env->sched;
    c->cache = env->cache;
    c->redis = env->redis;
    c->limits = env->limits;
    c->jobs = set->jobs;
    snprintf(c->consumer, sizeof c->consumer, "%s", env->instance);
    c->ttl_ms = env->ttl_ms;
    c->user_jobs = set->user_jobs > 0 ? set->user_jobs : 1;
    c->user_running = set->user_running;
    c->take.run = take_run;
    if (!ismd_redis_tasks_added(c->tasks)) {
        free(c);
        return NULL;
    }
    ism_cache_redis_schedule(c->redis, &c->take, 0);
    return c;
}

void ismd_cluster_free(ismd_cluster *c)
{
    free(c);
}

/* ---- jobs seen through any daemon ---------------------------------------------------- */

#define JOBREC_TTL_MS "7200000" /* outlives a finished job's 30 minutes and its longest run */

typedef struct jobtask {
    ism_redis_task base;       /* first: the tier hands this back */
    ismd_cluster *c;
    ismd_waiter *w;            /* lookup: who gets the answer; NULL: a record to write */
    bool delete;               /* without w: delete the job instead (JOB_DELETE_LUA) */
    char id[40], user[ISMD_QUEUE_USER_MAX], key[65], fmt[8];
    long long created_unix;
    long long first_try_ns;    /* a write or delete Redis did not take: its first attempt */
} jobtask;

/* A job's record write or DELETE that Redis did not take (unreachable, or its answer later
 * than the command timeout on a loaded machine: ISM_REDIS_COMMAND_TIMEOUT_MS) is tried again
 * this often, for at most JOBTASK_RETRY_FOR_NS; both are idempotent. Dropped, a DELETE the
 * client was told "canceled" never reached Redis (the job read running everywhere, and a dead
 * daemon's computation was never found abandoned: it ran on), and a record missing its
 * cjobs entry kept ABANDONED_LUA from ever finding its computation abandoned. */
#define JOBTASK_RETRY_NS 200000000LL
#define JOBTASK_RETRY_FOR_NS 60000000000LL

static long long jobtask_end(jobtask *j)
{
    ismd_redis_tasks *g = j->c->tasks;
    free(j);
    ismd_redis_tasks_ended(g);
    return 0;
}

/* True when Redis took all of it. */
static bool write_record(jobtask *j)
{
    char rec[KEY_MAX], created[24];
    ckey(j->c, rec, "jobrec:", j->id);
    snprintf(created, sizeof created, "%lld", j->created_unix);
    const char *argv[] = {"HSET", rec, "user", j->user, "key", j->key, "fmt", j->fmt,
                          "created", created, "daemon", j->c->consumer};
    size_t lens[12];
    for (int i = 0; i < 12; i++)
        lens[i] = strlen(argv[i]);
    redisReply *r = ism_cache_redis_call(j->c->redis, "jobrec_write", 12, argv, lens);
    if (!r)
        return false;
    freeReplyObject(r);
    const char *exp[] = {"PEXPIRE", rec, JOBREC_TTL_MS};
    size_t elens[] = {7, strlen(rec), strlen(JOBREC_TTL_MS)};
    if (!(r = ism_cache_redis_call(j->c->redis, "jobrec_expire", 3, exp, elens)))
        return false;
    freeReplyObject(r);
    char name[ISM_CACHE_NAME_MAX], set[KEY_MAX];
    if (!ism_cache_name(name, j->key, j->fmt))
        return true;
    ckey(j->c, set, "cjobs:", name); /* the jobs of one computation (ABANDONED_LUA) */
    const char *args[] = {set, j->id, JOBREC_TTL_MS};
    return run_script(j->c, "cjobs_add", CJOBS_ADD_LUA, 1, args, 3, NULL) == 0;
}

/* True when Redis took it. */
static bool delete_job(jobtask *j)
{
    char rec[KEY_MAX], now[24];
    ckey(j->c, rec, "jobrec:", j->id);
    wall_ms(now, 0);
    const char *args[] = {rec, ism_cache_redis_prefix(j->c->redis), j->id, JOBREC_TTL_MS, now};
    redisReply *r = NULL;
    if (run_script(j->c, "cluster_job_delete", JOB_DELETE_LUA, 1, args, 5, &r) < 0)
        return false;
    if (r->type == REDIS_REPLY_INTEGER && r->integer == 2) {
        ism_log_field f = ISM_LS("job", j->id);
        ism_log_fields(ISM_LOG_INFO, "cluster_abandoned_computation_canceled", &f, 1);
    }
    freeReplyObject(r);
    return true;
}

/* A record write or DELETE: done, or when to try again (JOBTASK_RETRY_NS). */
static long long write_or_delete(jobtask *j)
{
    if (j->delete ? delete_job(j) : write_record(j))
        return jobtask_end(j);
    long long now = ism_now_ns();
    if (!j->first_try_ns)
        j->first_try_ns = now;
    if (now - j->first_try_ns < JOBTASK_RETRY_FOR_NS)
        return now + JOBTASK_RETRY_NS;
    ism_log_field f[] = {ISM_LS("job", j->id), ISM_LS("what", j->delete ? "delete" : "record")};
    ism_log_fields(ISM_LOG_WARN, "cluster_job_write_lost", f, 2);
    return jobtask_end(j);
}

/* HMGET key fields... into out[] (copies, "" when missing). 1 found (first field set), 0 not,
 * -1 Redis unavailable. */
static int hash_fields(ismd_cluster *c, const char *key, const char *const *fields, int n,
                       char out[][256])
{
    const char *argv[8] = {"HMGET", key};
    size_t lens[8] = {5, strlen(key)};
    for (int i = 0; i < n && i < 6; i++) {
        argv[2 + i] = fields[i];
        lens[2 + i] = strlen(fields[i]);
    }
    redisReply *r = ism_cache_redis_call(c->redis, "hmget", 2 + n, argv, lens);
    if (!r)
        return -1;
    int found = 0;
    for (int i = 0; i < n; i++) {
        const char *v = r->type == REDIS_REPLY_ARRAY && (size_t)i < r->elements
                            ? reply_str(r->element[i]) : NULL;
        snprintf(out[i], 256, "%s", v ? v : "");
        found |= i == 0 && v != NULL;
    }
    freeReplyObject(r);
    return found;
}

/* The job's view from Redis into a JSON blob; status 200, 404 or 503. */
static unsigned lookup(jobtask *j, ism_blob **json)
{
    char rec[KEY_MAX], job[KEY_MAX], name[ISM_CACHE_NAME_MAX];
    char r[5][256], h[6][256];
    ckey(j->c, rec, "jobrec:", j->id);
    static const char *const RF[] = {"user", "key", "fmt", "created", "cancel"};
    int got = hash_fields(j->c, rec, RF, 5, r);
    if (got <= 0)
        return got < 0 ? 503 : 404;
    if (!ism_cache_name(name, r[1], r[2]))
        return 404;
    ckey(j->c, job, "job:", name);
    static const char *const HF[] = {"state", "progress", "status", "error", "started_ms",
                                     "cancel"};
    if (hash_fields(j->c, job, HF, 6, h) < 0)
        return 503;
    ismd_job_view v = {.id = j->id, .user = r[0], .key = r[1], .fmt = r[2],
                       .created_unix = (time_t)strtoll(r[3], NULL, 10),
                       .state = ISMD_JOB_QUEUED};
    char parts[3][ISM_CACHE_NAME_MAX];
    const char *names[3] = {parts[0], parts[1], parts[2]};
    ism_cache_name(parts[0], r[1], r[2]);
    ism_cache_name(parts[1], r[1], "stats.json");
    ism_cache_name(parts[2], r[1], "features.json");
    if (!ismd_job_state_parse(h[0], &v.state) && ism_cache_redis_count(j->c->redis, names, 3) == 3)
        v.state = ISMD_JOB_DONE; /* no computation on record: the mesh was there already */
    if (r[4][0] || (v.state < ISMD_JOB_DONE && h[5][0]))
        v.state = ISMD_JOB_CANCELED; /* the job deleted, or its computation canceled */
    v.progress = v.state == ISMD_JOB_DONE ? 1 : strtod(h[1], NULL);
    v.status = (unsigned)strtoul(h[2], NULL, 10);
    v.started_unix_ms = strtoll(h[4], NULL, 10);
    v.queue_ms = v.started_unix_ms ? (double)(v.started_unix_ms - v.created_unix * 1000) : 0;
    ism_blob *stats = NULL, *error = h[3][0] ? ism_blob_from_str(h[3]) : NULL;
    if (v.state == ISMD_JOB_DONE)
        ism_cache_redis_fetch(j->c->redis, &names[1], 1, &stats);
    v.stats = stats;
    v.error = error;
    json_t *o = ismd_job_view_json(&v);
    char *text = o ? json_dumps(o, JSON_COMPACT) : NULL;
    json_decref(o);
    ism_blob_unref(stats);
    ism_blob_unref(error);
    *json = text ? ism_blob_from_str(text) : NULL;
    free(text);
    return *json ? 200 : 503;
}

static long long jobtask_run(ism_redis_task *base, ism_cache_tier *t, bool stopping)
{
    jobtask *j = (jobtask *)base;
    (void)t;
    if (stopping)
        return jobtask_end(j); /* the tier is closing: the scheduler may be gone */
    if (!j->w)
        return write_or_delete(j);
    ism_blob *json = NULL;
    ismd_result r = {.status = lookup(j, &json), .content_type = "application/json"};
    r.body = json;
    if (ismd_redis_tasks_enter(j->c->tasks)) {
        j->w->done(j->w, &r);
        ismd_redis_tasks_leave(j->c->tasks);
    }
    ism_blob_unref(json);
    return jobtask_end(j);
}

static jobtask *jobtask_new(ismd_cluster *c, const char *id)
{
    jobtask *j = calloc(1, sizeof *j);
    if (!j)
        return NULL;
    if (!ismd_redis_tasks_added(c->tasks)) {
        free(j);
        return NULL;
    }
    j->c = c;
    j->base.run = jobtask_run;
    snprintf(j->id, sizeof j->id, "%s", id);
    return j;
}

void ismd_cluster_job_created(ismd_cluster *c, const char *id, const char *user,
                              const char *key, const char *fmt, long long created_unix)
{
    jobtask *j = jobtask_new(c, id);
    if (!j)
        return;
    snprintf(j->user, sizeof j->user, "%s", user);
    snprintf(j->key, sizeof j->key, "%s", key);
    snprintf(j->fmt, sizeof j->fmt, "%s", fmt);
    j->created_unix = created_unix;
    ism_cache_redis_schedule(c->redis, &j->base, 0);
}

bool ismd_cluster_job_lookup(ismd_cluster *c, const char *id, ismd_waiter *w)
{
    jobtask *j = jobtask_new(c, id);
    if (!j)
        return false;
    j->w = w;
    ism_cache_redis_schedule(c->redis, &j->base, 0);
    return true;
}

void ismd_cluster_job_delete(ismd_cluster *c, const char *id)
{
    jobtask *j = jobtask_new(c, id);
    if (!j)
        return;
    j->delete = true;
    ism_cache_redis_schedule(c->redis, &j->base, 0);
}
