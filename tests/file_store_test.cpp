// The store of uploaded files (server/store/file_store.h): content addressing and
// dedupe, the quota, pinning, paging, removal, expiry and the leftovers of
// writes cut short, and records surviving a new store on the same directory
// (a restart, or another instance on a shared data dir).
#include <gtest/gtest.h>

#include <sys/stat.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <algorithm>
#include <set>

#include "core/error.h"
#include "tests/support/temp_dir.h"
#include "server/store/file_store.h"
#include "server/common/service_error.h"

namespace fs = std::filesystem;
using nurbsrt::Error;
using nurbsrt::ErrorCode;
using nurbsrt::server::FileStore;
using nurbsrt::server::ServiceCode;
using nurbsrt::server::ServiceError;
using nurbsrt::server::sha256_hex;
using nurbsrt::server::StoredFile;

namespace {

class FileStoreTest : public ::testing::Test {
protected:
    nurbsrt::test::TempDir tmp_{"nurbsrt-filestore"};

    static StoredFile record(const std::string& bytes, int64_t created_ms, bool pinned = false) {
        StoredFile f;
        f.id = sha256_hex(bytes);
        f.format = "STEP";
        f.filename = "part.step";
        f.bytes = static_cast<int64_t>(bytes.size());
        f.created_ms = created_ms;
        f.pinned = pinned;
        f.summary_json = R"({"faces":3})";
        return f;
    }

    const std::string dir_ = tmp_.path() + "/files";  // created by the first put
};

TEST(Sha256, KnownVector) {
    // FIPS 180-2 appendix B.1: SHA-256("abc").
    EXPECT_EQ(sha256_hex("abc"), "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad");
}

TEST(FileStoreIds, OnlySha256Hex) {
    EXPECT_TRUE(FileStore::valid_id(sha256_hex("x")));
    EXPECT_FALSE(FileStore::valid_id(""));
    EXPECT_FALSE(FileStore::valid_id(std::string(64, 'A')));          // uppercase
    EXPECT_FALSE(FileStore::valid_id("../" + std::string(61, 'a')));  // never a path
    EXPECT_FALSE(FileStore::valid_id(std::string(63, 'a')));
}

TEST_F(FileStoreTest, StoresOnceByContent) {
    FileStore store(dir_, 1 << 20);
    StoredFile a = record("ISO-10303-21; a", 1000);
    EXPECT_EQ(store.put(a, "ISO-10303-21; a"), FileStore::PutOutcome::created);
    EXPECT_EQ(store.used_bytes(), 15);
    StoredFile again = record("ISO-10303-21; a", 2000);
    again.filename = "other.stp";
    EXPECT_EQ(store.put(again, "ISO-10303-21; a"), FileStore::PutOutcome::existing);
    EXPECT_EQ(again.created_ms, 1000);  // the stored record, not the new one
    EXPECT_EQ(again.filename, "part.step");
    EXPECT_EQ(store.used_bytes(), 15);
    const auto got = store.get(a.id);
    ASSERT_TRUE(got);
    EXPECT_EQ(got->summary_json, R"({"faces":3})");
    EXPECT_EQ(*store.open(a.id).bytes, "ISO-10303-21; a");
    // Another store on the same directory (a restart, another instance) sees it.
    FileStore other(dir_, 1 << 20);
    EXPECT_TRUE(other.get(a.id));
}

TEST_F(FileStoreTest, QuotaRefusesWithoutWriting) {
    FileStore store(dir_, 20);
    StoredFile a = record(std::string(15, 'a'), 1);
    EXPECT_EQ(store.put(a, std::string(15, 'a')), FileStore::PutOutcome::created);
    StoredFile b = record(std::string(6, 'b'), 2);
    EXPECT_EQ(store.put(b, std::string(6, 'b')), FileStore::PutOutcome::over_quota);
    EXPECT_FALSE(store.get(b.id));
    EXPECT_FALSE(fs::exists(store.content_path(b.id)));
    // The same bytes again need no room.
    StoredFile a2 = record(std::string(15, 'a'), 3);
    EXPECT_EQ(store.put(a2, std::string(15, 'a')), FileStore::PutOutcome::existing);
    EXPECT_TRUE(store.remove(a.id));
    EXPECT_EQ(store.put(b, std::string(6, 'b')), FileStore::PutOutcome::created);
}

TEST_F(FileStoreTest, OpenRemoveAndNotFound) {
    FileStore store(dir_, 1 << 20);
    EXPECT_FALSE(store.remove(sha256_hex("none")));
    try {
        store.open(sha256_hex("none"));
        FAIL() << "expected not_found";
    } catch (const ServiceError& e) {
        EXPECT_EQ(e.code(), ServiceCode::not_found);
        EXPECT_NE(std::string(e.what()).find(sha256_hex("none")), std::string::npos);  // names the id
    }
    StoredFile a = record("a", 1);
    store.put(a, "a");
    EXPECT_TRUE(store.remove(a.id));
    EXPECT_FALSE(store.get(a.id));
    EXPECT_FALSE(fs::exists(store.content_path(a.id)));
    EXPECT_FALSE(store.remove(a.id));
}

TEST_F(FileStoreTest, PinningSurvivesAndExpiryKeepsPinned) {
    FileStore store(dir_, 1 << 20);
    StoredFile old_file = record("old", 1000), pinned = record("pinned", 1000), fresh = record("fresh", 5000);
    store.put(old_file, "old");
    store.put(pinned, "pinned");
    store.put(fresh, "fresh");
    ASSERT_TRUE(store.set_pinned(pinned.id, true));
    EXPECT_TRUE(store.get(pinned.id)->pinned);
    EXPECT_FALSE(store.set_pinned(sha256_hex("none"), true));
    // A temporary file of a write cut short, and bytes whose record was never written, an hour old.
    const std::string tmp = dir_ + "/.tmp-cut-short";
    const std::string orphan = dir_ + "/" + sha256_hex("orphan") + ".cad";
    std::ofstream(tmp) << "x";
    std::ofstream(orphan) << "orphan";
    const auto old_time = fs::file_time_type::clock::now() - std::chrono::hours(2);
    fs::last_write_time(tmp, old_time);
    fs::last_write_time(orphan, old_time);
    EXPECT_EQ(store.expire(2000), 1);
    EXPECT_FALSE(store.get(old_file.id));
    EXPECT_TRUE(store.get(pinned.id));
    EXPECT_TRUE(store.get(fresh.id));
    EXPECT_FALSE(fs::exists(tmp));
    EXPECT_FALSE(fs::exists(orphan));
    ASSERT_TRUE(store.set_pinned(pinned.id, false));
    EXPECT_EQ(store.expire(2000), 1);
    EXPECT_FALSE(store.get(pinned.id));
}

TEST_F(FileStoreTest, ListPagesInBothOrders) {
    FileStore store(dir_, 1 << 20);
    std::vector<std::string> ids;
    for (int i = 0; i < 5; ++i) {
        const std::string bytes = "file " + std::to_string(i);
        StoredFile f = record(bytes, 1000 + i * 10);
        store.put(f, bytes);
        ids.push_back(f.id);
    }
    for (bool newest : {true, false}) {
        std::vector<std::string> seen;
        std::optional<std::string> cursor;
        int pages = 0;
        do {
            const auto page = store.list(newest, 2, cursor);
            for (const StoredFile& f : page.files) seen.push_back(f.id);
            cursor = page.next_cursor;
            ++pages;
        } while (cursor);
        EXPECT_EQ(pages, 3);
        std::vector<std::string> want = ids;
        if (newest) std::reverse(want.begin(), want.end());
        EXPECT_EQ(seen, want);
    }
    const auto first = store.list(true, 2, std::nullopt);
    ASSERT_TRUE(first.next_cursor);
    EXPECT_THROW(store.list(false, 2, first.next_cursor), Error);  // a cursor of the other order
    EXPECT_THROW(store.list(true, 2, std::string("n1.zz")), Error);
}

}  // namespace
