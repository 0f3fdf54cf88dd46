-- load_mix.lua — the wrk script of tests/bench/bench_load.py: a mix of GETs of cached meshes
-- and POSTs of new small requests (each one a distinct surface, so each is a computation).
-- bench_load.py writes the cached keys to the file named by the KEYS environment variable (one
-- per line) and the share of POSTs to NEW_SHARE (0..1). Counts every status per thread and
-- prints one line "status N=COUNT ..." at the end, so the caller can tell designed refusals
-- (503 queue full, 429) from errors.

local keys = {}
local new_share = tonumber(os.getenv("NEW_SHARE") or "0.1")
local threads = {}
local thread_id = 0
-- globals: what thread:get can read from each thread's state at the end
counter = 0
statuses = {}

local function load_keys()
  local f = assert(io.open(os.getenv("KEYS"), "r"))
  for line in f:lines() do
    if #line == 64 then keys[#keys + 1] = line end
  end
  f:close()
end

function setup(thread)
  thread_id = thread_id + 1
  thread:set("id", thread_id)
  threads[#threads + 1] = thread
end

function init(args)
  load_keys()
  math.randomseed(id * 7919)
end

function request()
  counter = counter + 1
  if math.random() < new_share then
    -- a sphere nobody asked for yet: a radius unique to this thread and request
    local r = string.format("%.9f", 0.4 + id * 0.01 + counter * 1e-8)
    local body = '{"expr": "x^2 + y^2 + z^2 - r^2", "params": {"r": ' .. r ..
                 '}, "depth": {"min": 2, "max": 4}}'
    return wrk.format("POST", "/v1/mesh", {["Content-Type"] = "application/json"}, body)
  end
  local key = keys[math.random(#keys)]
  return wrk.format("GET", "/v1/meshes/" .. key .. ".drc")
end

function response(status, headers, body)
  statuses[status] = (statuses[status] or 0) + 1
end

function done(summary, latency, requests)
  local total = {}
  for _, t in ipairs(threads) do
    local s = t:get("statuses")
    for code, n in pairs(s) do
      total[code] = (total[code] or 0) + n
    end
  end
  local parts = {}
  for code, n in pairs(total) do
    parts[#parts + 1] = code .. "=" .. n
  end
  table.sort(parts)
  io.write("status " .. table.concat(parts, " ") .. "\n")
end
