// The persistent job store (server/store/job_store.h): creation and listing with
// paging, state transitions, recovery of jobs a dead service left running
// (the database file reopened), the retention query, and clear errors for a
// corrupt or unwritable database.
#include <gtest/gtest.h>

#include <sys/stat.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>

#include "core/error.h"
#include "tests/support/temp_dir.h"
#include "server/store/job_store_sqlite.h"

namespace fs = std::filesystem;
using nurbsrt::Error;
using nurbsrt::ErrorCode;
using namespace nurbsrt::server;

namespace {

class JobStoreTest : public ::testing::Test {
protected:
    nurbsrt::test::TempDir tmp_{"nurbsrt-jobstore"};

    // A job with one input and `outputs` outputs (id from n, created at n seconds).
    static JobRecord make_job(int n, int outputs = 2) {
        JobRecord j;
        char id[40];
        std::snprintf(id, sizeof id, "%032x", n);
        j.id = id;
        j.created_ms = 1000LL * n;
        j.inputs.push_back({0, "part.step", "STEP", 1234});
        for (int i = 0; i < outputs; ++i) {
            JobOutput o;
            o.index = i;
            o.file = 0;
            o.kind = i % 2 ? OutputKind::conversion : OutputKind::render;
            o.options_json = i % 2 ? R"({"format":"iges"})" : R"({"width":32})";
            o.artifact =
                std::string("0-") + output_kind_name(o.kind) + "-" + std::to_string(i) + (i % 2 ? ".igs" : ".png");
            o.content_type = i % 2 ? "model/iges" : "image/png";
            j.outputs.push_back(o);
        }
        return j;
    }

    const std::string dir_ = tmp_.path(), db_ = dir_ + "/jobs.db";
};

TEST_F(JobStoreTest, CreateGetAndListWithPaging) {
    SqliteJobStore store(db_);
    for (int n = 1; n <= 5; ++n) {
        JobRecord j = make_job(n);
        store.create(j);
        EXPECT_GT(j.seq, 0);
    }
    const auto j3 = store.get(make_job(3).id);
    ASSERT_TRUE(j3);
    EXPECT_EQ(j3->state, JobState::queued);
    EXPECT_EQ(j3->created_ms, 3000);
    ASSERT_EQ(j3->inputs.size(), 1u);
    EXPECT_EQ(j3->inputs[0].filename, "part.step");
    ASSERT_EQ(j3->outputs.size(), 2u);
    EXPECT_EQ(j3->outputs[1].artifact, "0-conversion-1.igs");
    EXPECT_EQ(j3->outputs[1].options_json, R"({"format":"iges"})");
    EXPECT_FALSE(store.get(make_job(99).id));

    // Newest first, pages of 2: 5 4 | 3 2 | 1.
    std::vector<std::string> seen;
    std::optional<int64_t> after;
    int pages = 0;
    do {
        const auto page = store.list(std::nullopt, true, 2, after);
        for (const auto& j : page.jobs) seen.push_back(j.id);
        after = page.next_after;
        ++pages;
    } while (after && pages < 10);
    EXPECT_EQ(pages, 3);
    std::vector<std::string> expected;
    for (int n = 5; n >= 1; --n) expected.push_back(make_job(n).id);
    EXPECT_EQ(seen, expected);

    // Oldest first, one page of 5 exactly: no next page.
    const auto all = store.list(std::nullopt, false, 5, std::nullopt);
    ASSERT_EQ(all.jobs.size(), 5u);
    EXPECT_EQ(all.jobs.front().id, make_job(1).id);
    EXPECT_FALSE(all.next_after);

    // State filter.
    ASSERT_TRUE(store.claim_next(10000));
    const auto running = store.list(JobState::running, true, 10, std::nullopt);
    ASSERT_EQ(running.jobs.size(), 1u);
    EXPECT_EQ(running.jobs[0].id, make_job(1).id);
    EXPECT_EQ(store.count_by_state()[JobState::queued], 4);
    EXPECT_EQ(store.count_by_state()[JobState::running], 1);
    EXPECT_EQ(store.count_by_state()[JobState::failed], 0);
}

TEST_F(JobStoreTest, StateTransitions) {
    SqliteJobStore store(db_);
    JobRecord a = make_job(1), b = make_job(2);
    store.create(a);
    store.create(b);

    // Claimed in submission order.
    auto claimed = store.claim_next(5000);
    ASSERT_TRUE(claimed);
    EXPECT_EQ(claimed->id, a.id);
    EXPECT_EQ(claimed->state, JobState::running);
    EXPECT_EQ(claimed->attempts, 1);
    EXPECT_EQ(claimed->started_ms, 5000);

    EXPECT_TRUE(store.output_running(a.id, 0, 5100));
    EXPECT_TRUE(store.output_progress(a.id, 0, 0.5));
    EXPECT_DOUBLE_EQ(store.get(a.id)->outputs[0].progress, 0.5);
    EXPECT_TRUE(store.output_succeeded(a.id, 0, 777, R"({"faces":3})", 5200));
    EXPECT_TRUE(store.output_running(a.id, 1, 5300));
    EXPECT_TRUE(store.output_failed(a.id, 1, "unreadable_file", "bad file", 5400));
    EXPECT_EQ(store.finish(a.id, 5500), std::optional<JobState>(JobState::failed));
    const auto done = store.get(a.id);
    EXPECT_EQ(done->state, JobState::failed);
    EXPECT_EQ(done->finished_ms, 5500);
    EXPECT_EQ(done->error_code, "unreadable_file");
    EXPECT_NE(done->error_message.find("1 of 2 outputs failed"), std::string::npos);
    EXPECT_EQ(done->outputs[0].state, JobState::succeeded);
    EXPECT_EQ(done->outputs[0].artifact_bytes, 777);
    EXPECT_EQ(done->outputs[0].result_json, R"({"faces":3})");
    EXPECT_EQ(done->outputs[1].error_message, "bad file");
    // A finished job is not running: finishing again does nothing.
    EXPECT_FALSE(store.finish(a.id, 6000));

    // All outputs succeeded -> succeeded.
    claimed = store.claim_next(7000);
    ASSERT_TRUE(claimed);
    EXPECT_EQ(claimed->id, b.id);
    for (int i = 0; i < 2; ++i) {
        store.output_running(b.id, i, 7000);
        store.output_succeeded(b.id, i, 10, "", 7100);
    }
    EXPECT_EQ(store.finish(b.id, 7200), std::optional<JobState>(JobState::succeeded));
    EXPECT_TRUE(store.get(b.id)->error_code.empty());
    EXPECT_FALSE(store.claim_next(8000));  // nothing queued

    // DELETE: a finished job is removed; a running one becomes canceled.
    JobRecord c = make_job(3);
    store.create(c);
    ASSERT_TRUE(store.claim_next(9000));
    EXPECT_EQ(store.delete_job(c.id, 9100), JobStore::DeleteOutcome::canceling);
    EXPECT_EQ(store.get(c.id)->state, JobState::canceled);
    EXPECT_FALSE(store.running(c.id));
    EXPECT_FALSE(store.finish(c.id, 9200));  // the runner sees it is no longer running
    EXPECT_EQ(store.delete_job(c.id, 9300), JobStore::DeleteOutcome::canceling);
    EXPECT_TRUE(store.remove(c.id));
    EXPECT_EQ(store.delete_job(c.id, 9400), JobStore::DeleteOutcome::not_found);
    EXPECT_EQ(store.delete_job(a.id, 9500), JobStore::DeleteOutcome::removed);
    EXPECT_FALSE(store.get(a.id));
    EXPECT_FALSE(store.output_running(a.id, 0, 9600));  // transitions of a deleted job report it
}

TEST_F(JobStoreTest, RecoveryAfterRestart) {
    const JobRecord j1 = make_job(1), j2 = make_job(2), j3 = make_job(3);
    {
        SqliteJobStore store(db_);
        for (JobRecord j : {j1, j2, j3}) store.create(j);
        // j1 ran once and was cut short after its first output.
        store.claim_next(1000);
        store.output_running(j1.id, 0, 1000);
        store.output_succeeded(j1.id, 0, 5, "", 1100);
        store.output_running(j1.id, 1, 1200);
        // j2 had just started.
        store.claim_next(1300);
    }
    {
        SqliteJobStore store(db_);  // the service restarted
        const auto r = store.recover(2, 2000);
        EXPECT_EQ(r.requeued, (std::vector<std::string>{j1.id, j2.id}));
        EXPECT_TRUE(r.failed.empty());
        const auto a = store.get(j1.id);
        EXPECT_EQ(a->state, JobState::queued);
        EXPECT_EQ(a->attempts, 1);
        EXPECT_EQ(a->outputs[0].state, JobState::succeeded);  // kept
        EXPECT_EQ(a->outputs[1].state, JobState::queued);     // will run again
        EXPECT_EQ(store.get(j3.id)->state, JobState::queued);
        // The second run of j1 is cut short in the same output again; j2's second
        // run is cut short before any of its outputs started.
        EXPECT_EQ(store.claim_next(2100)->id, j1.id);
        store.output_running(j1.id, 1, 2100);
        EXPECT_EQ(store.claim_next(2100)->id, j2.id);
        EXPECT_EQ(store.get(j1.id)->attempts, 2);
        EXPECT_EQ(store.get(j1.id)->started_ms, 1000);  // the first start is kept
    }
    {
        SqliteJobStore store(db_);
        const auto r = store.recover(2, 3000);
        // Only runs of an output count against it: j1's output 1 ran twice and
        // fails; j2 lost two runs but none of its outputs ran, so it goes on.
        EXPECT_EQ(r.failed, (std::vector<std::string>{j1.id}));
        EXPECT_EQ(r.requeued, (std::vector<std::string>{j2.id}));
        EXPECT_EQ(store.get(j2.id)->state, JobState::queued);
        EXPECT_EQ(store.get(j2.id)->outputs[0].state, JobState::queued);
        const auto a = store.get(j1.id);
        EXPECT_EQ(a->state, JobState::failed);
        EXPECT_EQ(a->error_code, "interrupted");
        EXPECT_NE(a->error_message.find("interrupted by a service restart"), std::string::npos);
        EXPECT_EQ(a->finished_ms, 3000);
        EXPECT_EQ(a->outputs[0].state, JobState::succeeded);
        EXPECT_EQ(a->outputs[1].state, JobState::failed);
        EXPECT_EQ(a->outputs[1].error_code, "interrupted");
        EXPECT_EQ(store.get(j3.id)->state, JobState::queued);  // never started: untouched
        store.remove(j2.id);
        // A graceful stop puts a running job back without counting the run.
        EXPECT_EQ(store.claim_next(3100)->attempts, 1);
        store.requeue(j3.id);
        EXPECT_EQ(store.get(j3.id)->state, JobState::queued);
        EXPECT_EQ(store.get(j3.id)->attempts, 0);
        // A job deleted while running whose removal a crash cut short is removed at start.
        store.claim_next(3200);
        store.delete_job(j3.id, 3300);
    }
    SqliteJobStore store(db_);
    const auto r = store.recover(2, 4000);
    EXPECT_EQ(r.removed, (std::vector<std::string>{j3.id}));
    EXPECT_FALSE(store.get(j3.id));
}

TEST_F(JobStoreTest, RetentionQuery) {
    SqliteJobStore store(db_);
    for (int n = 1; n <= 3; ++n) {
        JobRecord j = make_job(n, 1);
        store.create(j);
    }
    // Job 1 finishes at 10 s, job 2 at 20 s; job 3 stays queued.
    for (int64_t t : {10000, 20000}) {
        const auto j = store.claim_next(t - 1);
        store.output_running(j->id, 0, t);
        store.output_succeeded(j->id, 0, 1, "", t);
        store.finish(j->id, t);
    }
    EXPECT_TRUE(store.finished_before(10000).empty());
    EXPECT_EQ(store.finished_before(15000), (std::vector<std::string>{make_job(1).id}));
    EXPECT_EQ(store.finished_before(99999).size(), 2u);  // never the queued one
}

TEST_F(JobStoreTest, CorruptDatabaseIsAClearError) {
    {
        std::ofstream out(db_, std::ios::binary);
        out << std::string(8192, 'x');
    }
    try {
        SqliteJobStore store(db_);
        FAIL() << "a corrupt database opened";
    } catch (const Error& e) {
        EXPECT_EQ(e.code(), ErrorCode::io);
        const std::string m = e.what();
        EXPECT_NE(m.find(db_), std::string::npos) << m;
        EXPECT_NE(m.find("not a database"), std::string::npos) << m;
    }
}

void expect_io_error_naming(const std::string& path) {
    try {
        SqliteJobStore store(path);
        ADD_FAILURE() << "the database " << path << " opened";
    } catch (const Error& e) {
        EXPECT_EQ(e.code(), ErrorCode::io);
        EXPECT_NE(std::string(e.what()).find(path), std::string::npos) << e.what();
    }
}

TEST_F(JobStoreTest, UnwritableDatabaseIsAClearError) {
    // Its directory is a regular file: nobody, not even root, can create it.
    { std::ofstream(dir_ + "/plain") << "x"; }
    expect_io_error_naming(dir_ + "/plain/jobs.db");
    // A directory where the file should be.
    fs::create_directory(db_);
    expect_io_error_naming(db_);
    fs::remove(db_);
    // A read-only directory (root ignores the permission).
    if (geteuid() != 0) {
        ASSERT_EQ(chmod(dir_.c_str(), 0500), 0);
        expect_io_error_naming(db_);
    }
}

TEST_F(JobStoreTest, NewerSchemaIsRefused) {
    { SqliteJobStore store(db_); }
    {
        // Bump the version as a newer nurbsrt would (the store has no SQL entry point: use the shell).
        std::string cmd = "sqlite3 '" + db_ + "' 'UPDATE schema_version SET version = 99'";
        if (std::system(cmd.c_str()) != 0) GTEST_SKIP() << "sqlite3 shell not available";
    }
    try {
        SqliteJobStore store(db_);
        FAIL() << "a newer schema was accepted";
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("schema version 99"), std::string::npos) << e.what();
    }
}

TEST_F(JobStoreTest, CallbacksBecomeDueWhenTheJobEndsAndAreClaimedOnce) {
    SqliteJobStore store(db_);
    JobRecord with = make_job(1, 1), without = make_job(2, 1);
    with.callback_url = "https://hooks.example.com/done";
    store.create(with);
    store.create(without);
    EXPECT_EQ(with.callback.state, CallbackState::waiting);
    EXPECT_EQ(store.get(with.id)->callback.state, CallbackState::waiting);
    EXPECT_EQ(store.get(without.id)->callback.state, CallbackState::none);
    EXPECT_FALSE(store.claim_callback(10'000, 1000));  // nothing ended yet
    for (int n = 0; n < 2; ++n) {
        auto c = store.claim_next(5000);
        ASSERT_TRUE(c);
        ASSERT_TRUE(store.output_running(c->id, 0, 5000));
        ASSERT_TRUE(store.output_succeeded(c->id, 0, 10, "{}", 6000));
        ASSERT_TRUE(store.finish(c->id, 7000));
    }
    EXPECT_EQ(store.get(without.id)->callback.state, CallbackState::none);
    auto due = store.claim_callback(7000, 1000);
    ASSERT_TRUE(due);
    EXPECT_EQ(due->id, with.id);
    EXPECT_EQ(due->callback_url, with.callback_url);
    EXPECT_EQ(due->state, JobState::succeeded);
    EXPECT_FALSE(store.claim_callback(7500, 1000));  // held while the attempt is in flight
    // A failed attempt: due again at next_ms, not before.
    CallbackAttempt retry{CallbackState::pending, 9000, 503, "answered HTTP 503", 7600};
    ASSERT_TRUE(store.callback_attempted(with.id, retry));
    EXPECT_FALSE(store.claim_callback(8999, 1000));
    due = store.claim_callback(9000, 1000);
    ASSERT_TRUE(due);
    EXPECT_EQ(due->callback.attempts, 1);
    EXPECT_EQ(due->callback.last_status, 503);
    EXPECT_EQ(due->callback.last_error, "answered HTTP 503");
    ASSERT_TRUE(store.callback_attempted(with.id, {CallbackState::delivered, 0, 204, "", 9100}));
    const auto done = store.get(with.id);
    EXPECT_EQ(done->callback.state, CallbackState::delivered);
    EXPECT_EQ(done->callback.attempts, 2);
    EXPECT_EQ(done->callback.done_ms, 9100);
    EXPECT_FALSE(store.callback_attempted(with.id, retry));  // no longer pending
    EXPECT_FALSE(store.claim_callback(100'000, 1000));
    // Kept across a reopen (a restart).
    SqliteJobStore reopened(db_);
    EXPECT_EQ(reopened.get(with.id)->callback.state, CallbackState::delivered);
}

TEST_F(JobStoreTest, AJobFailedByRecoveryHasItsCallbackDue) {
    {
        SqliteJobStore store(db_);
        JobRecord j = make_job(3, 1);
        j.callback_url = "https://hooks.example.com/done";
        store.create(j);
        for (int run = 0; run < 2; ++run) {  // two runs of its output cut short by restarts
            ASSERT_TRUE(store.claim_next(1000));
            ASSERT_TRUE(store.output_running(j.id, 0, 1000));
            store.recover(2, 2000);
        }
    }
    SqliteJobStore store(db_);
    const auto due = store.claim_callback(2000, 1000);
    ASSERT_TRUE(due);
    EXPECT_EQ(due->state, JobState::failed);
    EXPECT_EQ(due->error_code, "interrupted");
}

TEST_F(JobStoreTest, CrashesChargeOnlyTheOutputTheyCutShort) {
    // Six outputs, and a crash in each of them in turn, twice over: with a
    // budget of 3 runs per output nothing fails, although the job was cut
    // short 12 times (under one budget per job it failed at the second crash).
    const JobRecord j = make_job(5, 6);
    SqliteJobStore store(db_);
    JobRecord copy = j;
    store.create(copy);
    for (int round = 0; round < 2; ++round)
        for (int output = 0; output < 6; ++output) {
            const auto claim = store.claim_next(1000);
            ASSERT_TRUE(claim);
            ASSERT_TRUE(store.output_running(j.id, output, 1000));
            const auto r = store.recover(3, 2000);
            EXPECT_EQ(r.requeued, (std::vector<std::string>{j.id})) << round << " " << output;
        }
    // A third cut in output 2: that output has had its three runs and fails; the others go on.
    ASSERT_TRUE(store.claim_next(3000));
    ASSERT_TRUE(store.output_running(j.id, 2, 3000));
    EXPECT_EQ(store.recover(3, 4000).requeued, (std::vector<std::string>{j.id}));
    const auto after = store.get(j.id);
    EXPECT_EQ(after->state, JobState::queued);
    EXPECT_EQ(after->outputs[2].state, JobState::failed);
    EXPECT_EQ(after->outputs[2].error_code, "interrupted");
    EXPECT_EQ(after->outputs[0].state, JobState::queued);
}

TEST_F(JobStoreTest, AVersion1DatabaseIsMigrated) {
    // The schema as version 1 wrote it, with a finished job (the shell: the store has no SQL entry point).
    const std::string v1 =
        "CREATE TABLE schema_version (version INTEGER NOT NULL); INSERT INTO schema_version VALUES (1);"
        "CREATE TABLE jobs (seq INTEGER PRIMARY KEY AUTOINCREMENT, id TEXT NOT NULL UNIQUE, state TEXT NOT NULL,"
        " created_ms INTEGER NOT NULL, started_ms INTEGER NOT NULL DEFAULT 0, finished_ms INTEGER NOT NULL DEFAULT 0,"
        " attempts INTEGER NOT NULL DEFAULT 0, error_code TEXT NOT NULL DEFAULT '',"
        " error_message TEXT NOT NULL DEFAULT '');"
        "CREATE TABLE job_inputs (job_id TEXT NOT NULL REFERENCES jobs(id) ON DELETE CASCADE, idx INTEGER NOT NULL,"
        " filename TEXT NOT NULL, format TEXT NOT NULL, bytes INTEGER NOT NULL, PRIMARY KEY (job_id, idx));"
        "CREATE TABLE job_outputs (job_id TEXT NOT NULL REFERENCES jobs(id) ON DELETE CASCADE, idx INTEGER NOT NULL,"
        " file INTEGER NOT NULL, kind TEXT NOT NULL, options TEXT NOT NULL, artifact TEXT NOT NULL,"
        " content_type TEXT NOT NULL, state TEXT NOT NULL, progress REAL NOT NULL DEFAULT 0,"
        " error_code TEXT NOT NULL DEFAULT '', error_message TEXT NOT NULL DEFAULT '',"
        " artifact_bytes INTEGER NOT NULL DEFAULT 0, started_ms INTEGER NOT NULL DEFAULT 0,"
        " finished_ms INTEGER NOT NULL DEFAULT 0, result TEXT NOT NULL DEFAULT '', PRIMARY KEY (job_id, idx));"
        "INSERT INTO jobs(id, state, created_ms, finished_ms) VALUES ('" +
        std::string(32, 'e') + "', 'succeeded', 1000, 2000);";
    const std::string cmd = "sqlite3 '" + db_ + "' \"" + v1 + "\"";
    if (std::system(cmd.c_str()) != 0) GTEST_SKIP() << "sqlite3 shell not available";
    SqliteJobStore store(db_);
    const auto old = store.get(std::string(32, 'e'));
    ASSERT_TRUE(old);
    EXPECT_EQ(old->state, JobState::succeeded);
    EXPECT_EQ(old->callback.state, CallbackState::none);
    JobRecord j = make_job(4, 1);
    j.callback_url = "https://hooks.example.com/done";
    store.create(j);
    EXPECT_EQ(store.get(j.id)->callback_url, j.callback_url);
}

// The events a job's transitions append (JobEvent): in seq order from 1, the
// output's own, its artifact once it succeeded, the progress after each; read
// after a seq; gone with the job.
TEST_F(JobStoreTest, EventsFollowEveryTransitionInOrderAndGoWithTheJob) {
    SqliteJobStore store(db_);
    JobRecord j = make_job(1, 2);
    store.create(j);
    ASSERT_TRUE(store.claim_next(2000));
    ASSERT_TRUE(store.output_running(j.id, 0, 2100));
    ASSERT_TRUE(store.output_succeeded(j.id, 0, 77, "{}", 2300));
    EXPECT_FALSE(store.output_succeeded(j.id, 0, 77, "{}", 2400));  // no change, no event
    ASSERT_TRUE(store.output_failed(j.id, 1, "unreadable_file", "bad \"bytes\"", 2500));
    EXPECT_EQ(store.finish(j.id, 2600), std::optional<JobState>(JobState::failed));
    const auto events = store.events(j.id, 0, 100);
    ASSERT_TRUE(events);
    std::vector<std::string> seen;
    for (size_t i = 0; i < events->size(); ++i) {
        const JobEvent& e = (*events)[i];
        EXPECT_EQ(e.seq, static_cast<int64_t>(i + 1));
        seen.push_back(std::string(job_event_type_name(e.type)) + " " + e.data_json);
    }
    const std::vector<std::string> expected = {
        R"(state {"state":"queued"})",
        R"(state {"state":"running"})",
        R"(output {"artifact":"0-render-0.png","file":0,"kind":"render","output":0,"started_ms":2100,"state":"running"})",
        R"(progress {"artifact_bytes":0,"fraction":0.0,"outputs_done":0,"outputs_total":2})",
        R"(output {"artifact":"0-render-0.png","duration_ms":200,"file":0,"finished_ms":2300,"kind":"render","output":0,"started_ms":2100,"state":"succeeded"})",
        R"(artifact {"bytes":77,"content_type":"image/png","name":"0-render-0.png","output":0,"url":"/v1/jobs/00000000000000000000000000000001/artifacts/0-render-0.png"})",
        R"(progress {"artifact_bytes":77,"fraction":0.5,"outputs_done":1,"outputs_total":2})",
        R"(output {"artifact":"0-conversion-1.igs","error":{"code":"unreadable_file","message":"bad \"bytes\""},"file":0,"finished_ms":2500,"kind":"conversion","output":1,"state":"failed"})",
        R"(progress {"artifact_bytes":77,"fraction":1.0,"outputs_done":2,"outputs_total":2})",
        R"(state {"error":{"code":"unreadable_file","message":"1 of 2 outputs failed; first: bad \"bytes\""},"state":"failed"})"};
    EXPECT_EQ(seen, expected);
    EXPECT_EQ(events->front().time_ms, 1000);  // created at
    const auto after = store.events(j.id, 8, 100);
    ASSERT_TRUE(after);
    ASSERT_EQ(after->size(), 2u);
    EXPECT_EQ(after->front().seq, 9);
    EXPECT_EQ(store.events(j.id, 0, 3)->size(), 3u);
    EXPECT_TRUE(store.events(j.id, 10, 100)->empty());
    ASSERT_TRUE(store.remove(j.id));
    EXPECT_FALSE(store.events(j.id, 0, 100));
}

TEST_F(JobStoreTest, CancelRequeueAndRecoveryAppendStateEvents) {
    auto states = [](JobStore& store, const std::string& id) {
        std::vector<std::string> out;
        const auto events = store.events(id, 0, 100);
        for (const JobEvent& e : *events)
            if (e.type == JobEventType::state) out.push_back(e.data_json);
        return out;
    };
    JobRecord a = make_job(1, 1), b = make_job(2, 1);
    {
        SqliteJobStore store(db_);
        store.create(a);
        store.create(b);
        ASSERT_TRUE(store.claim_next(2000));  // a
        store.requeue(a.id);
        EXPECT_EQ(states(store, a.id), (std::vector<std::string>{R"({"state":"queued"})", R"({"state":"running"})",
                                                                 R"({"state":"queued"})"}));
        ASSERT_TRUE(store.claim_next(2100));  // a again
        ASSERT_TRUE(store.claim_next(2200));  // b
        ASSERT_TRUE(store.output_running(b.id, 0, 2300));
        EXPECT_EQ(store.delete_job(b.id, 2400), JobStore::DeleteOutcome::canceling);
        EXPECT_EQ(
            states(store, b.id).back(),
            R"({"error":{"code":"canceled","message":"deleted while running; removed once its current step stops"},"state":"canceled"})");
        ASSERT_TRUE(store.output_running(a.id, 0, 2500));
    }
    SqliteJobStore store(db_);  // a restart: a was running
    const RecoveryReport r = store.recover(3, 3000);
    EXPECT_EQ(r.requeued, std::vector<std::string>{a.id});
    EXPECT_EQ(states(store, a.id).back(), R"({"state":"queued"})");
    EXPECT_FALSE(store.events(b.id, 0, 100));  // removed with its events
}

}  // namespace
