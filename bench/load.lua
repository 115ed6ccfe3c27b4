-- wrk script of bench/load.sh: POSTs one CAD file as the raw body of
-- /v1/renders?<query>, counts the answers by status, and prints one RESULT line.
-- Arguments (after wrk's `--`): FILE MODE QUERY
--   MODE cached: the same bytes every time (the service's scene cache hits)
--   MODE unique: bytes made unique per request while the file stays valid, so the
--                content-addressed scene cache misses and every request imports:
--                STEP gets a comment after its ISO-10303-21; header line; IGES gets
--                the start of its first Start-section record (free text) overwritten,
--                keeping every 80-column record and all section counts intact.
local threads = {}

function setup(thread)
    table.insert(threads, thread)
    thread:set("id", #threads)
end

function init(args)
    local f = assert(io.open(args[1], "rb"))
    body = f:read("*a")
    f:close()
    mode = args[2]
    path = "/v1/renders?" .. args[3]
    headers = { ["Content-Type"] = "application/octet-stream" }
    is_step = body:find("^ISO%-10303%-21;") ~= nil
    n, ok, s429, s503, other = 0, 0, 0, 0, 0
    fixed = wrk.format("POST", path, headers, body)
end

local function unique_body()
    n = n + 1
    local tag = string.format("nurbsrt-bench %d.%d.%d", id, n, os.time())
    if is_step then
        return (body:gsub("^ISO%-10303%-21;", "ISO-10303-21;\n/* " .. tag .. " */", 1))
    end
    return tag .. body:sub(#tag + 1)
end

function request()
    if mode == "cached" then return fixed end
    return wrk.format("POST", path, headers, unique_body())
end

function response(status, hdrs, b)
    if status == 200 then ok = ok + 1
    elseif status == 429 then s429 = s429 + 1
    elseif status == 503 then s503 = s503 + 1
    else other = other + 1 end
end

function done(summary, latency, requests)
    local c = { ok = 0, s429 = 0, s503 = 0, other = 0 }
    for _, t in ipairs(threads) do
        for k, _ in pairs(c) do c[k] = c[k] + t:get(k) end
    end
    local e = summary.errors
    local secs = summary.duration / 1e6
    io.write(string.format(
        "RESULT requests=%d duration_s=%.2f rps=%.2f p50_ms=%.1f p90_ms=%.1f p99_ms=%.1f max_ms=%.1f ok=%d s429=%d s503=%d other=%d socket_errors=%d\n",
        summary.requests, secs, summary.requests / secs, latency:percentile(50) / 1000,
        latency:percentile(90) / 1000, latency:percentile(99) / 1000, latency.max / 1000,
        c.ok, c.s429, c.s503, c.other, e.connect + e.read + e.write + e.timeout))
end
