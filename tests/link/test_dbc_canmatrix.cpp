// The DBC reader against files another tool wrote (python3-canmatrix, Debian's package:
// tests/link/canmatrix_dbc.py) and against hand-written real-world syntax. Values cross
// both ways: frames canmatrix encoded decode here to canmatrix's values, and frames
// encoded here decode in canmatrix to the values we put in.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>

#include <unistd.h>

#include "firmware_link/dbc.hpp"
#include "rig/core/errors.hpp"

using namespace rig::link;
namespace fs = std::filesystem;

namespace {

const std::string kScript = std::string(RIG_SOURCE_DIR) + "/tests/link/canmatrix_dbc.py";

std::string run(const std::string& cmd) {
  FILE* p = popen(cmd.c_str(), "r");
  if (!p) return {};
  std::string out;
  char buf[4096];
  std::size_t n;
  while ((n = fread(buf, 1, sizeof buf, p)) > 0) out.append(buf, n);
  const int rc = pclose(p);
  EXPECT_EQ(rc, 0) << cmd << "\n" << out;
  return out;
}

// "a=1.5 b=2" -> {a: 1.5, b: 2}
std::map<std::string, double> values(std::istream& in) {
  std::map<std::string, double> m;
  std::string kv;
  while (in >> kv) {
    const auto eq = kv.find('=');
    m[kv.substr(0, eq)] = std::stod(kv.substr(eq + 1));
  }
  return m;
}

std::vector<uint8_t> unhex(const std::string& h) {
  std::vector<uint8_t> b;
  for (std::size_t i = 0; i + 1 < h.size(); i += 2) b.push_back(static_cast<uint8_t>(std::stoul(h.substr(i, 2), nullptr, 16)));
  return b;
}

CanFdFrame frame(uint32_t id, bool ext, const std::vector<uint8_t>& data) {
  CanFdFrame f;
  f.id = id;
  f.extended = ext;
  f.len = static_cast<uint8_t>(data.size());
  f.fd = data.size() > 8;
  std::copy(data.begin(), data.end(), f.data.begin());
  return f;
}

void expect_near_rel(double got, double want, const std::string& what) {
  EXPECT_NEAR(got, want, 1e-9 * std::max(1.0, std::fabs(want))) << what;
}

class CanmatrixDbc : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    // One folder per process: ctest runs the tests of this suite in parallel processes.
    dir_ = fs::path(::testing::TempDir()) / ("canmatrix_dbc-" + std::to_string(::getpid()));
    fs::create_directories(dir_);
    run("/usr/bin/python3 " + kScript + " export " + dir_.string() + " 2>/dev/null");
  }
  static fs::path dir_;
};
fs::path CanmatrixDbc::dir_;

}  // namespace

TEST_F(CanmatrixDbc, ReadsTheExportedFile) {
  const Dbc db = Dbc::parse_file((dir_ / "canmatrix.dbc").string());
  EXPECT_EQ(db.version(), "created by canmatrix");
  EXPECT_EQ(db.nodes(), (std::vector<std::string>{"DUT", "RIG"}));
  ASSERT_EQ(db.messages().size(), 5u);

  const DbcMessage* intel = db.find("SENSOR_INTEL");
  ASSERT_NE(intel, nullptr);
  EXPECT_EQ(intel->id, 0x123u);
  EXPECT_FALSE(intel->extended);
  EXPECT_EQ(intel->comment, "Intel layout, scaled counts");
  EXPECT_EQ(db.attribute(intel->attributes, "GenMsgCycleTime"), "1");
  EXPECT_EQ(db.attribute(intel->attributes, "VFrameFormat"), "StandardCAN");  // ENUM index -> name
  const DbcSignal* state = intel->signal("state");
  ASSERT_NE(state, nullptr);
  EXPECT_EQ(state->comment, "operating state");
  EXPECT_EQ(state->value_names.at(2), "FAULT");
  EXPECT_EQ(state->attributes.at("GenSigStartValue"), "1");
  EXPECT_NEAR(intel->signal("x_counts")->factor, 1e-6, 1e-20);
  ASSERT_EQ(intel->groups.size(), 1u);
  EXPECT_EQ(intel->groups[0].signals, (std::vector<std::string>{"counter", "x_counts"}));
  EXPECT_EQ(db.value_tables().at("STATES").at(1), "RUN");
  EXPECT_EQ(db.attribute(db.attributes(), "BusType"), "CAN FD");

  const DbcMessage* moto = db.find(0x18FF1234u, true);
  ASSERT_NE(moto, nullptr);
  EXPECT_EQ(moto->name, "SENSOR_MOTO");
  EXPECT_EQ(moto->comment, "Motorola layout\nover two lines");  // a comment over two lines
  EXPECT_TRUE(moto->signal("counter")->big_endian);
  EXPECT_EQ(moto->signal("x_g")->value_type, 1);
  EXPECT_EQ(db.find(0x18FF1234u, false), nullptr);

  const DbcMessage* mux = db.find("MUXED");
  EXPECT_TRUE(mux->signal("page")->multiplexor);
  EXPECT_EQ(mux->signal("b")->mux_value, 1);
  EXPECT_EQ(db.find("DOUBLE")->signal("d")->value_type, 2);
  const DbcMessage* fd = db.find("FD_BLOCK");
  EXPECT_EQ(fd->dlc, 64);
  EXPECT_EQ(db.attribute(fd->attributes, "VFrameFormat"), "StandardCAN_FD");
}

TEST_F(CanmatrixDbc, FramesCanmatrixEncodedDecodeToItsValues) {
  const Dbc db = Dbc::parse_file((dir_ / "canmatrix.dbc").string());
  std::ifstream in(dir_ / "frames.txt");
  std::string line;
  int n = 0;
  while (std::getline(in, line)) {
    std::istringstream ls(line);
    std::string name, hex;
    uint32_t id;
    int ext;
    ls >> name >> id >> ext >> hex;
    const auto want = values(ls);
    std::string err;
    const auto got = db.decode(frame(id, ext != 0, unhex(hex)), &err);
    ASSERT_TRUE(got) << line << " " << err;
    std::map<std::string, double> g;
    for (const auto& s : *got) g[s.name] = s.value;
    EXPECT_EQ(g.size(), want.size()) << line;  // the same multiplexed signals present
    for (const auto& [k, v] : want) {
      ASSERT_TRUE(g.count(k)) << line << ": " << k;
      expect_near_rel(g.at(k), v, line + ": " + k);
    }
    ++n;
  }
  EXPECT_EQ(n, 8);
}

TEST_F(CanmatrixDbc, FramesEncodedHereDecodeInCanmatrixToOurValues) {
  const Dbc db = Dbc::parse_file((dir_ / "canmatrix.dbc").string());
  struct Case {
    const char* msg;
    std::map<std::string, double> v;
  } cases[] = {
      {"SENSOR_INTEL", {{"counter", 4660}, {"x_counts", -0.5}, {"temp", 20.0625}, {"state", 1}}},
      {"SENSOR_MOTO", {{"counter", 0x1234}, {"x_g", -3.75}, {"small", -0.5}, {"flag", 1}}},
      {"MUXED", {{"page", 1}, {"b", 100.5}, {"common", 77}}},
      {"DOUBLE", {{"d", 1.0 / 3.0}}},
      {"FD_BLOCK", {{"counter", 9}, {"x0", 0.1}, {"x3", -0.2}, {"x7", 0.0001234}, {"tail", 0xBEEF}}},
  };
  std::ostringstream input;
  for (const auto& c : cases) {
    const DbcMessage* m = db.find(c.msg);
    ASSERT_NE(m, nullptr);
    std::vector<uint8_t> data(static_cast<std::size_t>(m->dlc));
    for (const auto& [k, v] : c.v) {
      const DbcSignal* s = m->signal(k);
      ASSERT_NE(s, nullptr) << k;
      dbc_insert_raw(data, s->start, s->length, s->big_endian, dbc_raw_of(*s, v));
    }
    char hex[3];
    input << (m->id) << " " << (m->extended ? 1 : 0) << " ";
    for (uint8_t b : data) {
      std::snprintf(hex, sizeof hex, "%02X", b);
      input << hex;
    }
    input << "\n";
    // And our own decoder reads back what we wrote.
    const auto self = db.decode(frame(m->id, m->extended, data));
    ASSERT_TRUE(self);
    for (const auto& s : *self)
      if (c.v.count(s.name)) expect_near_rel(s.value, c.v.at(s.name), std::string(c.msg) + "." + s.name);
  }
  const fs::path in = dir_ / "ours.txt";
  std::ofstream(in) << input.str();
  std::istringstream out(run("/usr/bin/python3 " + kScript + " decode " + (dir_ / "canmatrix.dbc").string() + " < " +
                             in.string() + " 2>/dev/null"));
  std::string line;
  std::size_t k = 0;
  while (std::getline(out, line)) {
    ASSERT_LT(k, std::size(cases));
    std::istringstream ls(line);
    const auto got = values(ls);
    for (const auto& [name, v] : cases[k].v) {
      ASSERT_TRUE(got.count(name)) << cases[k].msg << "." << name << " in '" << line << "'";
      expect_near_rel(got.at(name), v, std::string(cases[k].msg) + "." + name);
    }
    ++k;
  }
  EXPECT_EQ(k, std::size(cases));
}

// ---- hand-written files ---------------------------------------------------------------

namespace {

// Every section of the format, as CANdb++ writes it (environment variables, relation
// attributes, the pseudo-message of unsent signals, a comment over three lines).
const std::string kHandWritten = std::string(RIG_SOURCE_DIR) + "/tests/data/dbc/hand_written.dbc";
std::string error_of(const std::string& text) {
  try {
    Dbc::parse(text, "h.dbc");
  } catch (const rig::ConfigError& e) {
    return e.what();
  }
  return "no error";
}

}  // namespace

TEST(DbcHandWritten, ReadsEverySectionOfTheFormat) {
  const Dbc db = Dbc::parse_file(kHandWritten);
  EXPECT_EQ(db.version(), "1.2.3");
  EXPECT_EQ(db.comment(), "database comment");
  EXPECT_EQ(db.node_comments().at("ACC"), "the accelerometer");
  EXPECT_EQ(db.node_attributes().at("ACC").at("NodeLayer"), "app");
  EXPECT_EQ(db.attribute(db.attributes(), "DBName"), "hand");
  ASSERT_EQ(db.messages().size(), 2u);  // the pseudo-message is not a frame
  const DbcMessage* be = db.find(0x301, true);
  ASSERT_NE(be, nullptr);
  EXPECT_EQ(be->transmitters, (std::vector<std::string>{"ACC", "GW"}));
  EXPECT_EQ(be->signal("x")->receivers, (std::vector<std::string>{"GW", "ACC"}));
  EXPECT_EQ(be->signal("x")->comment, "counts,\nscaled to g; a ; inside a string\nand a \"quoted\" word");
  EXPECT_EQ(be->signal("heater")->value_names.at(1), "on");  // VAL_ naming a VAL_TABLE_
  EXPECT_EQ(be->signal("cnt")->attributes.at("GenSigInactiveValue"), "255");
  EXPECT_EQ(db.attribute(be->attributes, "GenMsgSendType"), "Cyclic");  // the default
  EXPECT_EQ(db.attribute(db.find(1024u, false)->attributes, "GenMsgSendType"), "Spontaneous");
  EXPECT_EQ(be->groups.at(0).name, "G");

  // Motorola 16-bit counter and int32 counts with a scale, in an extended-id frame.
  std::vector<uint8_t> d(8);
  dbc_insert_raw(d, 7, 16, true, 0xABCD);
  dbc_insert_raw(d, 23, 32, true, static_cast<uint32_t>(-1234567));
  EXPECT_EQ(d[0], 0xAB);
  EXPECT_EQ(d[1], 0xCD);
  CanFdFrame f;
  f.id = 0x301;
  f.extended = true;
  f.len = 8;
  std::copy(d.begin(), d.end(), f.data.begin());
  const auto s = db.decode(f);
  ASSERT_TRUE(s);
  EXPECT_EQ(s->at(0).value, 0xABCD);
  EXPECT_NEAR(s->at(1).value, -1.234567, 1e-12);
  f.extended = false;
  EXPECT_FALSE(db.decode(f));  // a standard id 0x301 is another frame

  // A 64-byte payload: the last byte, with an offset.
  CanFdFrame g;
  g.id = 1024;
  g.len = 64;
  g.fd = true;
  g.data[63] = 200;
  const auto a = db.decode(g);
  ASSERT_TRUE(a);
  EXPECT_EQ(a->at(0).value, 72);
  std::string err;
  g.len = 48;
  EXPECT_FALSE(db.decode(g, &err));
  EXPECT_EQ(err, "FD64: length 48, DBC says 64");
}

TEST(DbcHandWritten, MalformedFilesNameTheLine) {
  const std::string bo = "BO_ 256 M: 8 DUT\n SG_ a : 0|8@1+ (1,0) [0|1] \"\" X\n";
  EXPECT_EQ(error_of(bo + "CM_ SG_ 256 a \"never closed;\n"), "h.dbc:3: string not closed by '\"'");
  EXPECT_EQ(error_of(bo + "CM_ SG_ 256 a \"x\"\nVAL_ 256 a 1 \"one\";\n"), "h.dbc:3: CM_ statement not terminated by ';'");
  EXPECT_EQ(error_of(bo + "VAL_ 256 b 1 \"one\";\n"), "h.dbc:3: signal 'b' of message M is not defined");
  EXPECT_EQ(error_of(bo + "BA_ \"Nope\" BO_ 256 1;\n"), "h.dbc:3: attribute 'Nope' is not defined (BA_DEF_)");
  EXPECT_EQ(error_of(bo + "SIG_VALTYPE_ 256 a : 1;\n"), "h.dbc:3: signal a: float type needs 32 (or 64) bits, has 8");
  EXPECT_EQ(error_of("BO_ 256 M: 8 DUT\n SG_ a m1M : 0|8@1+ (1,0) [0|1] \"\" X\n"),
            "h.dbc:2: signal a: extended multiplexing ('m1M') is not supported");
  EXPECT_EQ(error_of("BO_ 256 M: 8 DUT\n SG_ a : 0|8@2+ (1,0) [0|1] \"\" X\n"),
            "h.dbc:2: byte order '2' is neither 0 (Motorola) nor 1 (Intel)");
  EXPECT_EQ(error_of("BO_ 256 M: 8 DUT\n SG_ a : 0|8@1+ (1,0 [0|1] \"\" X\n"), "h.dbc:2: expected ')', found '['");
  EXPECT_EQ(error_of("BO_ 256 M: 8 DUT\n SG_ a : 3|8@0+ (1,0) [0|1] \"\" X\n SG_ b : 7|8@0+ (1,0) [0|1] \"\" X\n"),
            "no error");
  EXPECT_EQ(error_of("BO_ 256 M: 1 DUT\n SG_ a : 3|8@0+ (1,0) [0|1] \"\" X\n"),
            "h.dbc:2: signal a (3|8@0) does not fit the message's 1 bytes");
  EXPECT_EQ(error_of("BO_ 256 M: 65 DUT\n"),
            "h.dbc:1: message M: length 65 is not a CAN frame length (0-8 bytes, or 12, 16, 20, 24, 32, 48, 64 for CAN FD)");
  EXPECT_EQ(error_of("BO_ 256 M: -1 DUT\n").find("h.dbc:1: message M: length -1 is not a CAN frame length"), 0u)
      << error_of("BO_ 256 M: -1 DUT\n");
  // A size no frame can have (an integrator's review: taken, then every frame skipped as
  // "length 8, DBC says 9"), and a signal of no bits ("does not fit the message's 8 bytes").
  EXPECT_EQ(error_of("BO_ 256 M: 9 DUT\n"),
            "h.dbc:1: message M: length 9 is not a CAN frame length (0-8 bytes, or 12, 16, 20, 24, 32, 48, 64 for CAN FD)");
  EXPECT_EQ(error_of("BO_ 256 M: 12 DUT\n SG_ a : 0|8@1+ (1,0) [0|1] \"\" X\n"), "no error");
  EXPECT_EQ(error_of("BO_ 256 M: 8 DUT\n SG_ a : 59|0@0+ (1,0) [0|1] \"\" X\n"),
            "h.dbc:2: signal a: bit length 0 (a signal has 1 to 64 bits)");
  EXPECT_EQ(error_of("BO_ 256 M: 8 DUT\n SG_ a : 0|8@1+ (1,0) [10.5|-10.5] \"\" X\n"),
            "h.dbc:2: signal a: range [10.5|-10.5] has its minimum above its maximum");
  EXPECT_EQ(error_of("BO_ 256 M: 8 DUT\n SG_ a : 0|8@1+ (1,0) [0|0] \"\" X\n"), "no error");
  EXPECT_EQ(error_of("BO_ 4096 M: 8 DUT\n"),
            "h.dbc:1: message M: standard id 4096 exceeds 11 bits (an extended id has bit 31 set in BO_)");
  EXPECT_EQ(error_of(bo + "FOO_ 1;\n"), "h.dbc:3: expected a DBC keyword (BO_, SG_, CM_, ...), found 'FOO_'");
  EXPECT_EQ(error_of("BO_ 256 M: 8 DUT\n SG_ a : 0|8@1+ (1,0) [0|1] \"\" X\n SG_ a : 8|8@1+ (1,0) [0|1] \"\" X\n"),
            "h.dbc:3: signal a defined twice in M");
  EXPECT_EQ(error_of("VERSION \"\"\n"), "h.dbc:1: no messages (BO_) defined");
  // A review's DBCs: a multiplexed signal in a message without a multiplexor was never decoded,
  // a float multiplexor was taken; a UTF-8 byte-order mark (Windows editors) was "0xEF".
  EXPECT_EQ(error_of("BO_ 256 M: 8 DUT\n SG_ a m1 : 0|8@1+ (1,0) [0|1] \"\" X\n"),
            "h.dbc:2: signal a is multiplexed (m1) but message M has no multiplexor (M)");
  EXPECT_EQ(error_of("BO_ 256 M: 8 DUT\n SG_ a M : 0|32@1+ (1,0) [0|1] \"\" X\n SG_ b m1 : 32|8@1+ (1,0) [0|1] \"\" X\n"
                     "SIG_VALTYPE_ 256 a : 1;\n"),
            "h.dbc:2: multiplexor a of M is a float (SIG_VALTYPE_): it must be an integer");
  EXPECT_EQ(error_of("\xEF\xBB\xBF" + bo), "no error");
  // A page the multiplexor's bits cannot carry (m9 under 2 bits) is never selected (a review).
  const std::string two_bits = "BO_ 256 M: 8 DUT\n SG_ p M : 0|2@1+ (1,0) [0|3] \"\" X\n";
  EXPECT_EQ(error_of(two_bits + " SG_ a m3 : 8|8@1+ (1,0) [0|1] \"\" X\n"), "no error");
  EXPECT_EQ(error_of(two_bits + " SG_ a m4 : 8|8@1+ (1,0) [0|1] \"\" X\n"),
            "h.dbc:3: signal a is on multiplexer page 4, which multiplexor p of M (2 bits: pages 0..3) cannot carry");
}

// Vector's CANdb++ writes DBC files in Windows-1252: a file that is not UTF-8 is read so (as
// cantools and canmatrix read it), its units and comments kept as UTF-8 text; lines do not move.
TEST(DbcHandWritten, AWindows1252FileIsReadAsCandbWritesIt) {
  const std::string text = "VERSION \"\"\nBO_ 256 M: 8 DUT\n SG_ t : 0|8@1+ (1,0) [0|1] \"\xB0" "C\" X\n"
                           " SG_ a : 8|16@1- (1,0) [0|1] \"\xB5g\" X\nCM_ SG_ 256 a \"x \x80 \x93y\x94 \x81\";\n";
  const Dbc db = Dbc::parse(text, "w.dbc");
  const DbcMessage* m = db.find(256u, false);
  ASSERT_NE(m, nullptr);
  EXPECT_EQ(m->signal("t")->unit, "\xC2\xB0" "C");
  EXPECT_EQ(m->signal("a")->unit, "\xC2\xB5g");
  EXPECT_EQ(m->signal("a")->comment, "x \xE2\x82\xAC \xE2\x80\x9Cy\xE2\x80\x9D \xC2\x81");  // euro, quotes; 0x81 undefined
  EXPECT_EQ(error_of(text + "VAL_ 256 b 1 \"one\";\n"), "h.dbc:6: signal 'b' of message M is not defined");
  // A file of both (CANdb++'s, edited later in a UTF-8 editor): each byte that is not UTF-8 is
  // read as 1252, the UTF-8 around it kept; a byte-order mark still skipped.
  const Dbc mixed = Dbc::parse("\xEF\xBB\xBF" "BO_ 256 M: 8 DUT\n SG_ a : 0|8@1+ (1,0) [0|1] \"\xC2\xB5g\" X\n"
                               " SG_ t : 8|8@1+ (1,0) [0|1] \"\xB0" "C\" X\n",
                               "m.dbc");
  EXPECT_EQ(mixed.find(256u, false)->signal("a")->unit, "\xC2\xB5g");
  EXPECT_EQ(mixed.find(256u, false)->signal("t")->unit, "\xC2\xB0" "C");
  // A UTF-8 file stays as it is.
  EXPECT_EQ(Dbc::parse("BO_ 256 M: 8 DUT\n SG_ a : 0|8@1+ (1,0) [0|1] \"\xC2\xB5g\" X\n", "u.dbc")
                .find(256u, false)->signal("a")->unit,
            "\xC2\xB5g");
}

TEST(DbcHandWritten, MotorolaBitNumberingMatchesTheSawtooth) {
  // 12 bits from bit 3 (MSB) of byte 0 to bit 0 of... : bits 3..0 of byte 0, 7..0 of byte 1.
  std::vector<uint8_t> d(8);
  dbc_insert_raw(d, 3, 12, true, 0xABC);
  EXPECT_EQ(d[0], 0x0A);
  EXPECT_EQ(d[1], 0xBC);
  EXPECT_EQ(dbc_extract_raw(d, 3, 12, true), 0xABCu);
  // Intel, not byte aligned, across three bytes.
  std::fill(d.begin(), d.end(), 0);
  dbc_insert_raw(d, 4, 16, false, 0xABCD);
  EXPECT_EQ(d[0], 0xD0);
  EXPECT_EQ(d[1], 0xBC);
  EXPECT_EQ(d[2], 0x0A);
  EXPECT_EQ(dbc_extract_raw(d, 4, 16, false), 0xABCDu);
}
