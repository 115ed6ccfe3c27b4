#include "server/common/request_log.h"

#include <nlohmann/json.hpp>

#include <chrono>
#include <cstdio>
#include <ctime>
#include <mutex>
#include <random>

namespace nurbsrt::server {
namespace {

std::string utc_timestamp() {
    const auto now = std::chrono::system_clock::now();
    const std::time_t t = std::chrono::system_clock::to_time_t(now);
    const auto ms = std::chrono::duration_cast<std::chrono::milliseconds>(now.time_since_epoch()).count() % 1000;
    std::tm tm{};
    gmtime_r(&t, &tm);
    char buf[64];
    std::snprintf(buf, sizeof buf, "%04d-%02d-%02dT%02d:%02d:%02d.%03dZ", tm.tm_year + 1900, tm.tm_mon + 1, tm.tm_mday,
                  tm.tm_hour, tm.tm_min, tm.tm_sec, static_cast<int>(ms));
    return buf;
}

void write_line(const nlohmann::json& j) {
    static std::mutex m;
    const std::string line = j.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace) + "\n";
    std::lock_guard<std::mutex> lock(m);
    std::fwrite(line.data(), 1, line.size(), stderr);
    std::fflush(stderr);
}

}  // namespace

std::string new_request_id() {
    thread_local std::mt19937_64 rng{std::random_device{}()};
    char buf[33];
    std::snprintf(buf, sizeof buf, "%016llx%016llx", static_cast<unsigned long long>(rng()),
                  static_cast<unsigned long long>(rng()));
    return buf;
}

std::string request_id_from_header(const std::string& v) {
    if (v.empty() || v.size() > 64) return new_request_id();
    for (const char c : v) {
        const bool ok = (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '.' ||
                        c == '_' || c == '-';
        if (!ok) return new_request_id();
    }
    return v;
}

void log_request(const RequestLogEntry& e) {
    nlohmann::json j = {
        {"ts", utc_timestamp()},    {"event", "request"}, {"request_id", e.request_id},   {"method", e.method},
        {"route", e.route},         {"status", e.status}, {"duration_ms", e.duration_ms}, {"bytes_in", e.bytes_in},
        {"bytes_out", e.bytes_out}, {"remote", e.remote}};
    if (!e.code.empty()) j["code"] = e.code;
    write_line(j);
}

void log_event(const std::string& event, const std::string& fields_json) {
    nlohmann::json j = {{"ts", utc_timestamp()}, {"event", event}};
    if (!fields_json.empty()) {
        const nlohmann::json f = nlohmann::json::parse(fields_json, nullptr, false);
        if (f.is_object())
            for (const auto& [k, v] : f.items()) j[k] = v;
    }
    write_line(j);
}

}  // namespace nurbsrt::server
