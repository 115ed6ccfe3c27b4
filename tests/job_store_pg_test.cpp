// The PostgreSQL job store (server/store/job_store_pg.h) against a real server:
// claims skip each other's outputs, an expired lease is taken over, the stale
// holder's updates are fenced off (never completed twice), cancel is seen by
// the heartbeat, the job finishes on whichever claim ends last, and an output
// whose lease expired max_attempts times fails as interrupted. Needs
// NURBSRT_TEST_PG_URL (tests/scale_out.sh sets it and runs these); skipped
// otherwise, saying so.
#include <gtest/gtest.h>

#include <chrono>
#include <cstdlib>
#include <thread>

#include "server/store/job_store_pg.h"
#include "server/store/pg_conn.h"

using namespace nurbsrt::server;

namespace {

std::string url() {
    const char* u = std::getenv("NURBSRT_TEST_PG_URL");
    return u ? u : "";
}

// A job of `files` inputs whose outputs take the files in turn (output i of file i % files).
JobRecord make_job(const std::string& id, int outputs, int files = 1) {
    JobRecord j;
    j.id = id;
    j.created_ms = 1000;
    for (int f = 0; f < files; ++f) j.inputs.push_back({f, "part.step", "STEP", 10});
    for (int i = 0; i < outputs; ++i) {
        JobOutput o;
        o.index = i;
        o.file = i % files;
        o.kind = OutputKind::conversion;
        o.options_json = R"({"format":"iges"})";
        o.artifact = std::to_string(o.file) + "-conversion-" + std::to_string(i) + ".igs";
        o.content_type = "model/iges";
        j.outputs.push_back(o);
    }
    return j;
}

class PgJobStoreTest : public ::testing::Test {
protected:
    void SetUp() override {
        if (url().empty()) GTEST_SKIP() << "NURBSRT_TEST_PG_URL not set: run tests/scale_out.sh";
        a_ = std::make_unique<PgJobStore>(url(), "test-a", 1.0);  // 1 s leases
        b_ = std::make_unique<PgJobStore>(url(), "test-b", 1.0);
        for (const std::string& id : a_->all_ids()) a_->remove(id);
    }
    std::unique_ptr<PgJobStore> a_, b_;
};

TEST_F(PgJobStoreTest, ClaimsSkipEachOtherAndTheLastFinishes) {
    // Two files of two outputs each: a claim takes one file's outputs (one read of it serves them).
    JobRecord j = make_job(std::string(32, 'a'), 4, 2);
    a_->create(j);
    auto ca = a_->claim_next(2000), cb = b_->claim_next(2000);
    ASSERT_TRUE(ca && cb);
    EXPECT_EQ(ca->run, (std::vector<int>{0, 2}));
    EXPECT_EQ(cb->run, (std::vector<int>{1, 3}));
    EXPECT_NE(ca->lease, cb->lease);
    EXPECT_FALSE(a_->claim_next(2000));  // nothing left
    EXPECT_EQ(a_->get(j.id)->state, JobState::running);
    for (const int k : {0, 2}) ASSERT_TRUE(a_->output_running(j.id, k, 2100, ca->lease));
    EXPECT_FALSE(a_->output_succeeded(j.id, 0, 5, "", 2200, cb->lease));  // not its lease
    ASSERT_TRUE(a_->output_succeeded(j.id, 0, 5, "", 2200, ca->lease));
    EXPECT_TRUE(a_->renew(*ca));  // output 2 still holds the claim's lease
    ASSERT_TRUE(a_->output_succeeded(j.id, 2, 5, "", 2250, ca->lease));
    EXPECT_FALSE(a_->renew(*ca));                                                   // nothing of it left open
    EXPECT_EQ(a_->finish(j.id, 2300), std::optional<JobState>(JobState::running));  // file 1 still runs on b
    for (const int k : {1, 3}) ASSERT_TRUE(b_->output_running(j.id, k, 2400, cb->lease));
    ASSERT_TRUE(b_->output_succeeded(j.id, 3, 5, "", 2450, cb->lease));
    ASSERT_TRUE(b_->output_failed(j.id, 1, "unreadable_file", "bad", 2500, cb->lease));
    EXPECT_EQ(b_->finish(j.id, 2600), std::optional<JobState>(JobState::failed));
    const auto done = a_->get(j.id);
    EXPECT_EQ(done->error_code, "unreadable_file");
    EXPECT_EQ(done->outputs[0].state, JobState::succeeded);
    EXPECT_EQ(done->outputs[2].state, JobState::succeeded);
}

TEST_F(PgJobStoreTest, ExpiredLeaseIsTakenOverAndTheStaleRunIsFenced) {
    JobRecord j = make_job(std::string(32, 'b'), 1);
    a_->create(j);
    auto ca = a_->claim_next(1000);
    ASSERT_TRUE(ca);
    ASSERT_TRUE(a_->output_running(j.id, 0, 1000, ca->lease));
    EXPECT_TRUE(a_->renew(*ca));
    EXPECT_FALSE(b_->claim_next(1000));  // leased
    std::this_thread::sleep_for(std::chrono::milliseconds(1300));
    auto cb = b_->claim_next(3000);  // a "died": its lease expired
    ASSERT_TRUE(cb);
    EXPECT_EQ(cb->attempts, 2);
    EXPECT_FALSE(a_->renew(*ca));  // the heartbeat tells a it lost the output
    ASSERT_TRUE(b_->output_running(j.id, 0, 3000, cb->lease));
    EXPECT_FALSE(a_->output_succeeded(j.id, 0, 1, "", 3100, ca->lease));  // fenced
    EXPECT_TRUE(b_->output_succeeded(j.id, 0, 1, "", 3200, cb->lease));
    EXPECT_FALSE(b_->output_succeeded(j.id, 0, 1, "", 3300, cb->lease));  // once only
    EXPECT_EQ(b_->finish(j.id, 3400), std::optional<JobState>(JobState::succeeded));
    EXPECT_EQ(a_->get(j.id)->attempts, 2);
}

TEST_F(PgJobStoreTest, CancelStopsTheHeartbeatAndTwiceExpiredFails) {
    JobRecord j = make_job(std::string(32, 'c'), 1);
    a_->create(j);
    auto ca = a_->claim_next(1000);
    ASSERT_TRUE(ca);
    EXPECT_EQ(b_->delete_job(j.id, 1100), JobStore::DeleteOutcome::canceling);
    EXPECT_FALSE(a_->renew(*ca));                     // seen by the runner's next heartbeat
    EXPECT_EQ(a_->finish(j.id, 1200), std::nullopt);  // so it removes the job
    EXPECT_TRUE(a_->remove(j.id));

    JobRecord k = make_job(std::string(32, 'd'), 1);
    a_->create(k);
    ASSERT_TRUE(a_->claim_next(1000));
    std::this_thread::sleep_for(std::chrono::milliseconds(1200));
    ASSERT_TRUE(b_->claim_next(2000));  // second attempt
    std::this_thread::sleep_for(std::chrono::milliseconds(1200));
    EXPECT_FALSE(a_->claim_next(3000, 2));  // expired twice: failed, not claimed
    const auto done = a_->get(k.id);
    EXPECT_EQ(done->state, JobState::failed);
    EXPECT_EQ(done->error_code, "interrupted");
    EXPECT_EQ(done->outputs[0].error_code, "interrupted");
}

TEST_F(PgJobStoreTest, GracefulStopRequeuesWithoutCountingTheRun) {
    JobRecord j = make_job(std::string(32, 'e'), 1);
    a_->create(j);
    auto ca = a_->claim_next(1000);
    ASSERT_TRUE(ca);
    a_->requeue(*ca);
    EXPECT_EQ(a_->get(j.id)->state, JobState::queued);
    EXPECT_EQ(a_->get(j.id)->attempts, 0);
    auto cb = b_->claim_next(2000);  // at once: no lease to wait for
    ASSERT_TRUE(cb);
    EXPECT_EQ(cb->attempts, 1);
}

TEST_F(PgJobStoreTest, ACallbackIsDueOnceTheLastOutputEndsAndOneInstanceTakesIt) {
    JobRecord j = make_job(std::string(32, 'f'), 1);
    j.callback_url = "https://hooks.example.com/done";
    a_->create(j);
    EXPECT_EQ(b_->get(j.id)->callback.state, CallbackState::waiting);
    auto c = a_->claim_next(1000);
    ASSERT_TRUE(c);
    ASSERT_TRUE(a_->output_running(j.id, 0, 1100, c->lease));
    ASSERT_TRUE(a_->output_succeeded(j.id, 0, 5, "{}", 1200, c->lease));
    EXPECT_EQ(a_->finish(j.id, 1300), std::optional<JobState>(JobState::succeeded));
    auto due = b_->claim_callback(1300, 60'000);
    ASSERT_TRUE(due);
    EXPECT_EQ(due->callback.state, CallbackState::pending);
    EXPECT_FALSE(a_->claim_callback(1400, 60'000));  // held by b's attempt
    ASSERT_TRUE(b_->callback_attempted(j.id, {CallbackState::pending, 2000, 0, "no answer: Connection", 1500}));
    EXPECT_FALSE(a_->claim_callback(1999, 60'000));
    due = a_->claim_callback(2000, 60'000);  // the retry, on the other instance
    ASSERT_TRUE(due);
    ASSERT_TRUE(a_->callback_attempted(j.id, {CallbackState::failed, 0, 500, "answered HTTP 500", 2100}));
    const auto done = b_->get(j.id);
    EXPECT_EQ(done->callback.state, CallbackState::failed);
    EXPECT_EQ(done->callback.attempts, 2);
    EXPECT_EQ(done->callback.last_status, 500);
    EXPECT_FALSE(b_->callback_attempted(j.id, {CallbackState::delivered, 0, 200, "", 2200}));
}

TEST_F(PgJobStoreTest, AVersion1SchemaIsMigrated) {
    a_.reset();
    b_.reset();
    {
        nurbsrt::server::PgConn c(url());
        c.exec("DROP TABLE IF EXISTS job_events, job_outputs, job_inputs, jobs, schema_version");
        c.exec("CREATE TABLE schema_version (version INTEGER NOT NULL); INSERT INTO schema_version VALUES (1)");
        c.exec(
            "CREATE TABLE jobs (seq BIGSERIAL PRIMARY KEY, id TEXT NOT NULL UNIQUE, state TEXT NOT NULL, "
            "created_ms BIGINT NOT NULL, started_ms BIGINT NOT NULL DEFAULT 0, finished_ms BIGINT NOT NULL "
            "DEFAULT 0, attempts INTEGER NOT NULL DEFAULT 0, error_code TEXT NOT NULL DEFAULT '', "
            "error_message TEXT NOT NULL DEFAULT '')");
        c.exec(
            "CREATE TABLE job_inputs (job_id TEXT NOT NULL REFERENCES jobs(id) ON DELETE CASCADE, idx INTEGER "
            "NOT NULL, filename TEXT NOT NULL, format TEXT NOT NULL, bytes BIGINT NOT NULL, "
            "PRIMARY KEY (job_id, idx))");
        c.exec(
            "CREATE TABLE job_outputs (job_id TEXT NOT NULL REFERENCES jobs(id) ON DELETE CASCADE, idx INTEGER "
            "NOT NULL, file INTEGER NOT NULL, kind TEXT NOT NULL, options TEXT NOT NULL, artifact TEXT NOT NULL, "
            "content_type TEXT NOT NULL, state TEXT NOT NULL, progress DOUBLE PRECISION NOT NULL DEFAULT 0, "
            "error_code TEXT NOT NULL DEFAULT '', error_message TEXT NOT NULL DEFAULT '', artifact_bytes BIGINT "
            "NOT NULL DEFAULT 0, started_ms BIGINT NOT NULL DEFAULT 0, finished_ms BIGINT NOT NULL DEFAULT 0, "
            "result TEXT NOT NULL DEFAULT '', attempts INTEGER NOT NULL DEFAULT 0, lease_token TEXT NOT NULL "
            "DEFAULT '', lease_owner TEXT NOT NULL DEFAULT '', lease_expires_ms BIGINT NOT NULL DEFAULT 0, "
            "completions INTEGER NOT NULL DEFAULT 0, PRIMARY KEY (job_id, idx))");
        c.exec("INSERT INTO jobs(id, state, created_ms) VALUES ($1, 'succeeded', 1000)", {std::string(32, '9')});
    }
    PgJobStore store(url(), "test-migrate", 1.0);
    const auto old = store.get(std::string(32, '9'));
    ASSERT_TRUE(old);
    EXPECT_EQ(old->callback.state, CallbackState::none);
    JobRecord j = make_job(std::string(32, '8'), 1);
    j.callback_url = "https://hooks.example.com/done";
    store.create(j);
    EXPECT_EQ(store.get(j.id)->callback_url, j.callback_url);
    nurbsrt::server::PgConn c(url());
    EXPECT_EQ(c.exec("SELECT MAX(version) FROM schema_version").i64(0, 0), 3);
}

// Events appended by two instances running one job's files: one sequence, in
// commit order, each output's end once (a fenced stale update appends none),
// read alike by either instance.
TEST_F(PgJobStoreTest, EventsOfTwoInstancesFormOneSequence) {
    JobRecord j = make_job(std::string(32, 'e'), 4, 2);
    a_->create(j);
    auto ca = a_->claim_next(2000), cb = b_->claim_next(2000);
    ASSERT_TRUE(ca && cb);
    for (const int k : {0, 2}) ASSERT_TRUE(a_->output_running(j.id, k, 2100, ca->lease));
    for (const int k : {1, 3}) ASSERT_TRUE(b_->output_running(j.id, k, 2100, cb->lease));
    ASSERT_TRUE(b_->output_succeeded(j.id, 1, 5, "", 2200, cb->lease));
    EXPECT_FALSE(a_->output_succeeded(j.id, 1, 5, "", 2200, ca->lease));  // not its lease: no event
    ASSERT_TRUE(a_->output_succeeded(j.id, 0, 5, "", 2300, ca->lease));
    ASSERT_TRUE(a_->output_succeeded(j.id, 2, 5, "", 2300, ca->lease));
    ASSERT_TRUE(b_->output_succeeded(j.id, 3, 5, "", 2400, cb->lease));
    EXPECT_EQ(a_->finish(j.id, 2500), std::optional<JobState>(JobState::succeeded));
    const auto on_a = a_->events(j.id, 0, 1000), on_b = b_->events(j.id, 0, 1000);
    ASSERT_TRUE(on_a && on_b);
    ASSERT_EQ(on_a->size(), on_b->size());
    int running = 0, artifacts = 0;
    for (size_t i = 0; i < on_b->size(); ++i) {
        const JobEvent& e = (*on_b)[i];
        EXPECT_EQ(e.seq, static_cast<int64_t>(i + 1));
        EXPECT_EQ(e.data_json, (*on_a)[i].data_json);
        if (e.type == JobEventType::state && e.data_json == R"({"state":"running"})") ++running;
        if (e.type == JobEventType::artifact) ++artifacts;
    }
    EXPECT_EQ(running, 1);  // two claims, one job becoming running
    EXPECT_EQ(artifacts, 4);
    EXPECT_EQ(on_b->front().data_json, R"({"state":"queued"})");
    EXPECT_EQ(on_b->back().data_json, R"({"state":"succeeded"})");
    EXPECT_EQ(on_b->at(on_b->size() - 2).data_json,
              R"({"artifact_bytes":20,"fraction":1.0,"outputs_done":4,"outputs_total":4})");
    ASSERT_TRUE(a_->remove(j.id));
    EXPECT_FALSE(b_->events(j.id, 0, 10));
}

}  // namespace
