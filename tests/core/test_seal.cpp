// rig/seal: HMAC-SHA256 against RFC 4231's test vectors, the key's checks, and a seal's check.
#include "rig/seal/seal.hpp"

#include <filesystem>
#include <fstream>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "rig/core/errors.hpp"

namespace fs = std::filesystem;
using rig::seal::Key;

namespace {

Key key_of(std::string bytes) { return Key{"test", std::move(bytes), "test"}; }

std::string folder(const std::string& name) {
  const fs::path d = fs::temp_directory_path() / ("seal-" + name + "-" + std::to_string(::getpid()));
  fs::remove_all(d);
  fs::create_directories(d);
  return d.string();
}

}  // namespace

// RFC 4231, test cases 1, 2 and 6 (a key longer than the block size).
TEST(Seal, HmacSha256IsRfc4231s) {
  EXPECT_EQ(rig::seal::text_mac(key_of(std::string(20, '\x0b')), "Hi There"),
            "b0344c61d8db38535ca8afceaf0bf12b881dc200c9833da726e9376c2e32cff7");
  EXPECT_EQ(rig::seal::text_mac(key_of("Jefe"), "what do ya want for nothing?"),
            "5bdcc146bf60754e6a042426089575c75a003f089d2739839dec58b964ec3843");
  EXPECT_EQ(rig::seal::text_mac(key_of(std::string(131, '\xaa')),
                                "Test Using Larger Than Block-Size Key - Hash Key First"),
            "60e431591ee0b67f0d8a26aacbf5b77f8e0bc6213728c5140546040f0ee37f54");
}

TEST(Seal, AKeyIsTheOwnersAloneAndLongEnough) {
  const std::string d = folder("key");
  const std::string k = d + "/k";
  std::ofstream(k) << std::string(31, 'a');
  fs::permissions(k, fs::perms::owner_read | fs::perms::owner_write, fs::perm_options::replace);
  try {
    rig::seal::load_key(k);
    ADD_FAILURE() << "a 31-byte key must be refused";
  } catch (const rig::ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find(k + ": station key has 31 bytes; at least 32"), std::string::npos) << e.what();
  }
  std::ofstream(k) << std::string(32, 'a');
  fs::permissions(k, fs::perms::group_read, fs::perm_options::add);
  EXPECT_THROW(rig::seal::load_key(k), rig::ConfigError);
  fs::permissions(k, fs::perms::owner_read, fs::perm_options::replace);
  const Key key = rig::seal::load_key(k);
  EXPECT_EQ(key.id.size(), 16u);
  EXPECT_THROW(rig::seal::load_key(d + "/missing"), rig::ConfigError);
  EXPECT_THROW(rig::seal::load_key(d), rig::ConfigError);
}

TEST(Seal, ACheckNamesWhatChangedWhatIsMissingAndWhatIsNotSealed) {
  const std::string d = folder("check");
  std::ofstream(d + "/a.txt") << "alpha";
  fs::create_directories(d + "/sub");
  std::ofstream(d + "/sub/b.bin") << "beta";
  const Key k = key_of(std::string(32, 'k'));
  const std::string text = rig::seal::make_seal(d, k, {{"a.txt", "", false, ""}, {"sub/b.bin", "", false, ""},
                                                       {"c.json", "{}", true, ""}});
  std::ofstream(d + "/seal.json") << text;
  std::ofstream(d + "/c.json") << "{}";
  EXPECT_TRUE(rig::seal::check_seal(d, d + "/seal.json", k, {"a.txt"}).ok);
  const auto unsealed = rig::seal::check_seal(d, d + "/seal.json", k, {"d.txt"});
  ASSERT_EQ(unsealed.problems.size(), 1u);
  EXPECT_EQ(unsealed.problems[0], "d.txt: not sealed (the folder has none)");  // a killed run's passport
  std::ofstream(d + "/d.txt") << "delta";
  EXPECT_EQ(rig::seal::check_seal(d, d + "/seal.json", k, {"d.txt"}).problems.at(0), "d.txt: not sealed");
  fs::remove(d + "/d.txt");
  std::ofstream(d + "/sub/b.bin") << "Beta";
  fs::remove(d + "/c.json");
  const auto c = rig::seal::check_seal(d, d + "/seal.json", k);
  EXPECT_FALSE(c.ok);
  ASSERT_EQ(c.problems.size(), 2u);
  EXPECT_EQ(c.problems[0], "c.json: sealed, but missing");
  EXPECT_EQ(c.problems[1], "sub/b.bin: changed since it was sealed");
  // The same file list under another key's seal is not this key's.
  const auto other = rig::seal::check_seal(d, d + "/seal.json", key_of(std::string(32, 'o')));
  EXPECT_FALSE(other.ok);
  // A MAC moved from one entry to another breaks the seal's own MAC.
  nlohmann::json j = nlohmann::json::parse(text);
  j["files"]["a.txt"] = j["files"]["c.json"];
  std::ofstream(d + "/seal.json") << j.dump();
  const auto moved = rig::seal::check_seal(d, d + "/seal.json", k);
  ASSERT_EQ(moved.problems.size(), 1u);
  EXPECT_NE(moved.problems[0].find("its list of files or its outcome was edited"), std::string::npos);
  fs::remove_all(d);
}

// Two entries folded into one whose path holds "TAB mac NL" give the same text under the seal's
// MAC: without the key a forger dropped both files from the list and deleted them, and the check
// said ok (an auditor's review). Paths and outcomes with control characters, MACs that are not 64
// hex digits, fields rig does not write and another algorithm's name are refused.
TEST(Seal, ASealWhoseListReadsBackTwoWaysIsRefused) {
  const std::string d = folder("fold");
  std::ofstream(d + "/a.txt") << "alpha";
  std::ofstream(d + "/b.txt") << "beta";
  std::ofstream(d + "/c.txt") << "gamma";
  const Key k = key_of(std::string(32, 'k'));
  const std::string text =
      rig::seal::make_seal(d, k, {{"a.txt", "", false, ""}, {"b.txt", "", false, ""}, {"c.txt", "", false, ""}}, "PASS");
  ASSERT_TRUE(rig::seal::check_seal(d, d + "/seal.json", k).problems.size() == 1u);  // no seal.json yet
  const auto check = [&](const nlohmann::json& j) {
    std::ofstream(d + "/seal.json") << j.dump();
    return rig::seal::check_seal(d, d + "/seal.json", k);
  };
  const nlohmann::json good = nlohmann::json::parse(text);
  EXPECT_TRUE(check(good).ok);
  // a.txt and b.txt folded into one entry; the file of that name holds b.txt's bytes, both gone.
  nlohmann::json folded = good;
  const std::string ma = folded["files"]["a.txt"], mb = folded["files"]["b.txt"];
  folded["files"].erase("a.txt");
  folded["files"].erase("b.txt");
  const std::string name = "a.txt\t" + ma + "\nb.txt";
  folded["files"][name] = mb;
  std::ofstream(d + "/" + name) << "beta";
  fs::remove(d + "/a.txt");
  fs::remove(d + "/b.txt");
  const auto f = check(folded);
  EXPECT_FALSE(f.ok);
  ASSERT_EQ(f.problems.size(), 1u);
  EXPECT_NE(f.problems[0].find("not a path rig seals (a control character)"), std::string::npos) << f.problems[0];
  EXPECT_NE(f.problems[0].find("a.txt\\x09"), std::string::npos) << "shown, not sent: " << f.problems[0];
  fs::remove(d + "/" + name);
  std::ofstream(d + "/a.txt") << "alpha";
  std::ofstream(d + "/b.txt") << "beta";
  EXPECT_TRUE(check(good).ok);
  nlohmann::json bad = good;
  bad["files"]["c.txt"] = std::string(64, 'A');
  EXPECT_NE(check(bad).problems.at(0).find("files.c.txt: not a MAC (64 hex digits)"), std::string::npos);
  bad = good;
  bad["outcome"] = "PASS\nc.txt";
  EXPECT_NE(check(bad).problems.at(0).find("a control character, which rig never writes"), std::string::npos);
  bad = good;
  bad["note"] = "forged";
  EXPECT_NE(check(bad).problems.at(0).find("field 'note' is not a rig.seal/1 field"), std::string::npos);
  bad = good;
  bad["schema"] = 1;  // it ended rig verify with exit 4 and a JSON library's words (a re-check)
  EXPECT_NE(check(bad).problems.at(0).find("not a rig.seal/1 seal"), std::string::npos);
  bad = good;
  bad["algorithm"] = "NONE";
  EXPECT_NE(check(bad).problems.at(0).find("rig seals with HMAC-SHA256"), std::string::npos);
  fs::remove_all(d);
}

// A MAC already taken (`Entry::mac`, a record sealed once and carried) is sealed as it is: an
// edit after it taken is never vouched for.
TEST(Seal, AMacCarriedFromAnEarlierSealKeepsAnEditOut) {
  const std::string d = folder("carried");
  std::ofstream(d + "/a.cap") << "as written";
  const Key k = key_of(std::string(32, 'k'));
  const std::string mac = rig::seal::file_mac(k, d + "/a.cap");
  std::ofstream(d + "/a.cap") << "as forged!";  // the same size
  std::ofstream(d + "/seal.json") << rig::seal::make_seal(d, k, {{"a.cap", "", false, mac}});
  const auto c = rig::seal::check_seal(d, d + "/seal.json", k);
  ASSERT_EQ(c.problems.size(), 1u);
  EXPECT_EQ(c.problems[0], "a.cap: changed since it was sealed");
  fs::remove_all(d);
}
