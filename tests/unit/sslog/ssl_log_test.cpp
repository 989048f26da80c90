// SPDX-License-Identifier: Apache-2.0
// The SSL log file format (apps/sslog, docs/log-files.md): what the writer writes reads back the
// same, plain and gzip, and an independent reader (read_ssl_log.py, written from the format's
// description) reads it alike; damaged files are refused naming the record and its byte offset;
// and `ubersim replay` sends every record's payload, unchanged and in order, on loopback.
#include "ssl_log.hpp"

#include <arpa/inet.h>
#include <gtest/gtest.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <future>
#include <iomanip>
#include <iterator>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "../../common/multicast_receiver.hpp"
#include "../../common/temp_dir.hpp"
#include "../../common/run_ubersim.hpp"

namespace {

namespace fs = std::filesystem;
using ubersim::sslog::LogFormatError;
using ubersim::sslog::LogReader;
using ubersim::sslog::LogRecord;
using ubersim::sslog::LogWriter;
using ubersim::sslog::LogWriterOptions;
using ubersim::sslog::MessageType;
using ubersim::testing::CliResult;
using ubersim::testing::Receiver;
using ubersim::testing::RunUbersim;

const std::string kPythonReader = UBERSIM_SOURCE_DIR "/tests/unit/sslog/read_ssl_log.py";
// The system's Python: the script uses the standard library only, and must not depend on the
// interpreter first on PATH.
const std::string kSystemPython = "/usr/bin/python3";

fs::path TempDir() { return ubersim::testing::ProcessTempDir("ubersim_sslog_test"); }
// Removes this process's TempDir when the tests end.
[[maybe_unused]] ::testing::Environment* const kRemoveTempDir =
    ::testing::AddGlobalTestEnvironment(new ubersim::testing::RemoveDirAtEnd(TempDir()));

std::string ReadBytes(const fs::path& file) {
  std::ifstream in(file, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

void WriteBytes(const fs::path& file, const std::string& bytes) {
  std::ofstream out(file, std::ios::binary | std::ios::trunc);
  out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
}

std::int64_t BigEndian(const std::string& bytes, std::size_t at, int size) {
  std::uint64_t v = 0;
  for (int i = 0; i < size; ++i) v = (v << 8) | static_cast<unsigned char>(bytes.at(at + i));
  return static_cast<std::int64_t>(v);
}

// Records of every kind a file holds: each known type, an unknown id, an empty payload, every
// byte value, and a payload of 100 kB (more than one read chunk).
std::vector<LogRecord> SampleRecords() {
  const std::int64_t t0 = 1'700'000'000'123'456'789;
  std::string every_byte;
  for (int b = 0; b < 256; ++b) every_byte.push_back(static_cast<char>(b));
  std::string big(100'000, '\0');
  std::uint32_t x = 12345;
  for (char& c : big) c = static_cast<char>((x = x * 1664525u + 1013904223u) >> 24);
  return {
      {t0, 4, "vision frame 1"},
      {t0 + 16'000'000, 5, "tracked frame"},
      {t0 + 16'000'000, 3, "referee"},
      {t0 + 20'000'000, 2, "legacy vision"},
      {t0 + 21'000'000, 0, ""},
      {t0 + 22'000'000, 1002, "a team's own"},
      {t0 + 32'000'000, 4, every_byte},
      {t0 + 48'000'000, 4, big},
      {t0 + 64'000'000, 1, std::string("\0\0\0\0", 4)},
  };
}

void WriteLog(const fs::path& file, const std::vector<LogRecord>& records, LogWriterOptions options = {}) {
  LogWriter writer(file.string(), options);
  for (const LogRecord& r : records) writer.Write(r.timestamp_ns, r.type, r.payload);
  writer.Close();
}

// Every record of `file`, by LogReader, with each record's offset.
std::vector<LogRecord> ReadLog(const fs::path& file, std::vector<std::int64_t>* offsets = nullptr) {
  LogReader reader(file.string());
  std::vector<LogRecord> out;
  while (auto r = reader.Next()) {
    out.push_back(std::move(*r));
    if (offsets) offsets->push_back(reader.RecordOffset());
  }
  EXPECT_EQ(reader.Records(), static_cast<std::int64_t>(out.size()));
  return out;
}

void ExpectSameRecords(const std::vector<LogRecord>& got, const std::vector<LogRecord>& want) {
  ASSERT_EQ(got.size(), want.size());
  for (std::size_t i = 0; i < want.size(); ++i) {
    EXPECT_EQ(got[i].timestamp_ns, want[i].timestamp_ns) << "record " << i + 1;
    EXPECT_EQ(got[i].type, want[i].type) << "record " << i + 1;
    EXPECT_TRUE(got[i].payload == want[i].payload) << "record " << i + 1 << ": payload differs";
  }
}

// SHA-1 (FIPS 180-4), for the lines compared with the Python reader's hashlib.sha1.
std::string Sha1Hex(const std::string& message) {
  std::uint32_t h[5] = {0x67452301, 0xEFCDAB89, 0x98BADCFE, 0x10325476, 0xC3D2E1F0};
  std::string m = message;
  const std::uint64_t bits = static_cast<std::uint64_t>(message.size()) * 8;
  m.push_back(static_cast<char>(0x80));
  while (m.size() % 64 != 56) m.push_back('\0');
  for (int i = 7; i >= 0; --i) m.push_back(static_cast<char>(bits >> (8 * i)));
  const auto rotl = [](std::uint32_t v, int n) { return (v << n) | (v >> (32 - n)); };
  for (std::size_t block = 0; block < m.size(); block += 64) {
    std::uint32_t w[80];
    for (int t = 0; t < 16; ++t) w[t] = static_cast<std::uint32_t>(BigEndian(m, block + 4 * t, 4));
    for (int t = 16; t < 80; ++t) w[t] = rotl(w[t - 3] ^ w[t - 8] ^ w[t - 14] ^ w[t - 16], 1);
    std::uint32_t a = h[0], b = h[1], c = h[2], d = h[3], e = h[4];
    for (int t = 0; t < 80; ++t) {
      std::uint32_t f, k;
      if (t < 20)
        f = (b & c) | (~b & d), k = 0x5A827999;
      else if (t < 40)
        f = b ^ c ^ d, k = 0x6ED9EBA1;
      else if (t < 60)
        f = (b & c) | (b & d) | (c & d), k = 0x8F1BBCDC;
      else
        f = b ^ c ^ d, k = 0xCA62C1D6;
      const std::uint32_t temp = rotl(a, 5) + f + e + k + w[t];
      e = d, d = c, c = rotl(b, 30), b = a, a = temp;
    }
    h[0] += a, h[1] += b, h[2] += c, h[3] += d, h[4] += e;
  }
  char hex[41];
  for (int i = 0; i < 5; ++i) std::snprintf(hex + 8 * i, 9, "%08x", h[i]);
  return hex;
}

TEST(SslLogSha1, KnownAnswers) {
  EXPECT_EQ(Sha1Hex(""), "da39a3ee5e6b4b0d3255bfef95601890afd80709");
  EXPECT_EQ(Sha1Hex("abc"), "a9993e364706816aba3e25717850c26c9cd0d89d");
  EXPECT_EQ(Sha1Hex(std::string(1000, 'a')), "291e9a6c66994949b57ba5e650361e98fc36b1ba");
}

// ---------------------------------------------------------------------------------------------

TEST(SslLogFormat, PlainFileRoundTripsAndHasTheDocumentedLayout) {
  const fs::path file = TempDir() / "plain.log";
  const auto records = SampleRecords();
  WriteLog(file, records);
  std::vector<std::int64_t> offsets;
  ExpectSameRecords(ReadLog(file, &offsets), records);

  // The bytes themselves: the header, then each record's big-endian fields at its offset.
  const std::string bytes = ReadBytes(file);
  ASSERT_GE(bytes.size(), 16u);
  EXPECT_EQ(bytes.substr(0, 16), std::string("SSL_LOG_FILE\0\0\0\1", 16));
  std::size_t at = 16;
  for (std::size_t i = 0; i < records.size(); ++i) {
    EXPECT_EQ(offsets[i], static_cast<std::int64_t>(at));
    EXPECT_EQ(BigEndian(bytes, at, 8), records[i].timestamp_ns);
    EXPECT_EQ(BigEndian(bytes, at + 8, 4), records[i].type);
    EXPECT_EQ(BigEndian(bytes, at + 12, 4), static_cast<std::int64_t>(records[i].payload.size()));
    at += 16 + records[i].payload.size();
  }
  EXPECT_EQ(at, bytes.size());
  EXPECT_FALSE(LogReader(file.string()).Compressed());
}

TEST(SslLogFormat, GzipFileRoundTripsAndAMisnamedOneReadsToo) {
  const fs::path dir = TempDir();
  const auto records = SampleRecords();
  WriteLog(dir / "z.log.gz", records);
  const std::string bytes = ReadBytes(dir / "z.log.gz");
  ASSERT_GE(bytes.size(), 2u);
  EXPECT_EQ(static_cast<unsigned char>(bytes[0]), 0x1F);
  EXPECT_EQ(static_cast<unsigned char>(bytes[1]), 0x8B);
  EXPECT_LT(bytes.size(), 110'000u);  // compressed: the 100 kB record is random, the rest shrinks
  ExpectSameRecords(ReadLog(dir / "z.log.gz"), records);
  EXPECT_TRUE(LogReader((dir / "z.log.gz").string()).Compressed());

  fs::copy_file(dir / "z.log.gz", dir / "misnamed.log", fs::copy_options::overwrite_existing);
  ExpectSameRecords(ReadLog(dir / "misnamed.log"), records);

  // Two gzip members one after the other (`cat a.gz b.gz`, split inside a record) are one stream,
  // as gunzip reads it.
  WriteLog(dir / "whole.log", records);
  const std::string plain = ReadBytes(dir / "whole.log");
  WriteBytes(dir / "part1", plain.substr(0, 50));
  WriteBytes(dir / "part2", plain.substr(50));
  int status = std::system(("gzip -c " + (dir / "part1").string() + " > " + (dir / "two.log.gz").string() +
                            " && gzip -c " + (dir / "part2").string() + " >> " + (dir / "two.log.gz").string())
                               .c_str());
  ASSERT_EQ(status, 0) << "gzip";
  ExpectSameRecords(ReadLog(dir / "two.log.gz"), records);
}

TEST(SslLogFormat, AnEmptyLogIsTheHeaderAlone) {
  const fs::path file = TempDir() / "empty.log";
  WriteLog(file, {});
  EXPECT_EQ(ReadBytes(file), std::string("SSL_LOG_FILE\0\0\0\1", 16));
  EXPECT_TRUE(ReadLog(file).empty());
}

TEST(SslLogFormat, IndexIsTheLastRecordWithEveryRecordsOffset) {
  const fs::path file = TempDir() / "indexed.log";
  const auto records = SampleRecords();
  WriteLog(file, records, {.write_index = true});
  std::vector<std::int64_t> offsets;
  auto read = ReadLog(file, &offsets);
  ASSERT_EQ(read.size(), records.size() + 1);
  const LogRecord index = read.back();
  read.pop_back();
  offsets.pop_back();
  ExpectSameRecords(read, records);
  const std::size_t n = records.size();
  EXPECT_EQ(index.timestamp_ns, 0);
  EXPECT_EQ(index.type, 6);
  EXPECT_EQ(index.payload.size(), 8 * n + 15);
  EXPECT_EQ(ubersim::sslog::ParseIndexPayload(index.payload), offsets);
  EXPECT_EQ(offsets.front(), 16);

  // Found as §4.3 of the format says a reader finds it: from the end of the file.
  const std::string bytes = ReadBytes(file);
  ASSERT_EQ(bytes.substr(bytes.size() - 7), "INDEXED");
  const std::int64_t length = BigEndian(bytes, bytes.size() - 15, 8);
  EXPECT_EQ(length, static_cast<std::int64_t>(16 + 8 * n + 15));
  const std::size_t start = bytes.size() - static_cast<std::size_t>(length) + 16;
  for (std::size_t i = 0; i < n; ++i) {
    const std::int64_t offset = BigEndian(bytes, start + 8 * i, 8);
    EXPECT_EQ(offset, offsets[i]) << "entry " << i;
    // The record there is record i: its timestamp, type and size.
    EXPECT_EQ(BigEndian(bytes, offset, 8), records[i].timestamp_ns) << "entry " << i;
    EXPECT_EQ(BigEndian(bytes, offset + 8, 4), records[i].type) << "entry " << i;
    EXPECT_EQ(BigEndian(bytes, offset + 12, 4), static_cast<std::int64_t>(records[i].payload.size())) << "entry " << i;
  }
  // An index of nothing is well-formed too: no offsets, its length, INDEXED.
  WriteLog(TempDir() / "indexed-empty.log", {}, {.write_index = true});
  const auto only_index = ReadLog(TempDir() / "indexed-empty.log");
  ASSERT_EQ(only_index.size(), 1u);
  EXPECT_EQ(only_index[0].payload, std::string("\0\0\0\0\0\0\0\x1f"
                                               "INDEXED",
                                               15));
  EXPECT_EQ(ubersim::sslog::ParseIndexPayload(only_index[0].payload), std::vector<std::int64_t>{});
  EXPECT_EQ(ubersim::sslog::ParseIndexPayload("INDEXED"), std::nullopt);
  EXPECT_EQ(ubersim::sslog::ParseIndexPayload(std::string("\0\0\0\0\0\0\0\x1e"
                                                          "INDEXED",
                                                          15)),
            std::nullopt);
}

TEST(SslLogFormat, IndexNeedsAnUncompressedFile) {
  const fs::path file = TempDir() / "indexed.log.gz";
  try {
    LogWriter writer(file.string(), {.write_index = true});
    FAIL() << "wrote an index into a gzip file";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find(file.string()), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("uncompressed"), std::string::npos) << e.what();
  }
}

TEST(SslLogFormat, TimestampsThatGoBackAreRaisedToTheLast) {
  const fs::path file = TempDir() / "back.log";
  LogWriter writer(file.string());
  writer.Write(100, MessageType::kVision2014, "a");
  writer.Write(50, MessageType::kVision2014, "b");
  writer.Write(200, MessageType::kReferee2013, "c");
  writer.Write(199, MessageType::kReferee2013, "d");
  EXPECT_EQ(writer.Records(), 4);
  EXPECT_EQ(writer.ClampedTimestamps(), 2);
  writer.Close();
  writer.Close();  // twice: nothing
  EXPECT_THROW(writer.Write(300, MessageType::kVision2014, "late"), std::runtime_error);
  std::vector<std::int64_t> times;
  for (const LogRecord& r : ReadLog(file)) times.push_back(r.timestamp_ns);
  EXPECT_EQ(times, (std::vector<std::int64_t>{100, 100, 200, 200}));
}

TEST(SslLogFormat, WriteErrorsNameTheFileAndTheSystemsReason) {
  const std::string file = (TempDir() / "no-such-dir" / "x.log").string();
  for (const std::string& name : {file, file + ".gz"}) {
    try {
      LogWriter writer(name);
      FAIL() << "created " << name;
    } catch (const std::runtime_error& e) {
      EXPECT_NE(std::string(e.what()).find(name), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find("No such file or directory"), std::string::npos) << e.what();
    }
  }
  try {
    LogReader reader(file);
    FAIL() << "opened " << file;
  } catch (const std::runtime_error& e) {
    EXPECT_EQ(std::string(e.what()), "cannot open SSL log file " + file + ": No such file or directory");
  }
}

TEST(SslLogFormat, AFullDiskIsAnErrorOfCloseNamingTheFile) {
  if (!fs::exists("/dev/full")) GTEST_SKIP() << "no /dev/full";
  LogWriter writer("/dev/full");  // buffered: the header reaches the device on Close
  writer.Write(1, MessageType::kVision2014, "frame");
  try {
    writer.Close();
    FAIL() << "closed a file on a full device";
  } catch (const std::runtime_error& e) {
    EXPECT_EQ(std::string(e.what()), "cannot close SSL log file /dev/full: No space left on device");
  }
}

TEST(SslLogFormat, MessageTypeNames) {
  EXPECT_EQ(ubersim::sslog::MessageTypeName(4), "SSL_VISION_2014");
  EXPECT_EQ(ubersim::sslog::MessageTypeName(5), "SSL_VISION_TRACKER_2020");
  EXPECT_EQ(ubersim::sslog::MessageTypeName(3), "SSL_REFBOX_2013");
  EXPECT_EQ(ubersim::sslog::MessageTypeName(2), "SSL_VISION_2010");
  EXPECT_EQ(ubersim::sslog::MessageTypeName(6), "SSL_INDEX_2021");
  EXPECT_EQ(ubersim::sslog::MessageTypeName(0), "BLANK");
  EXPECT_EQ(ubersim::sslog::MessageTypeName(1), "UNKNOWN");
  EXPECT_EQ(ubersim::sslog::MessageTypeName(1002), "type 1002");
}

// ---------------------------------------------------------------------------------------------
// The independent reader.

// Runs `command` through the shell; its stdout, and its exit status in `status`.
std::string Capture(const std::string& command, int& status) {
  std::string out;
  FILE* pipe = popen(command.c_str(), "r");
  if (!pipe) return out;
  std::array<char, 4096> buf{};
  while (fgets(buf.data(), buf.size(), pipe)) out += buf.data();
  status = pclose(pipe);
  return out;
}

// What read_ssl_log.py prints, as this reader sees the file.
std::string LinesOf(const fs::path& file) {
  std::string out;
  std::optional<std::vector<std::int64_t>> index;
  for (const LogRecord& r : ReadLog(file)) {
    out += std::to_string(r.timestamp_ns) + " " + std::to_string(r.type) + " " + std::to_string(r.payload.size()) +
           " " + Sha1Hex(r.payload) + "\n";
    index = r.type == 6 ? ubersim::sslog::ParseIndexPayload(r.payload) : std::nullopt;
  }
  if (index) {
    out += "index";
    for (const std::int64_t o : *index) out += " " + std::to_string(o);
    out += "\n";
  }
  return out;
}

TEST(SslLogFormat, AnIndependentReaderReadsWhatTheWriterWrote) {
  if (!fs::exists(kSystemPython)) GTEST_SKIP() << kSystemPython << " is missing";
  const fs::path dir = TempDir();
  const auto records = SampleRecords();
  WriteLog(dir / "py.log", records);
  WriteLog(dir / "py.log.gz", records);
  WriteLog(dir / "py-indexed.log", records, {.write_index = true});
  for (const char* name : {"py.log", "py.log.gz", "py-indexed.log"}) {
    int status = -1;
    const std::string theirs = Capture(kSystemPython + " " + kPythonReader + " " + (dir / name).string(), status);
    EXPECT_EQ(status, 0) << name;
    const std::string ours = LinesOf(dir / name);
    EXPECT_EQ(theirs, ours) << name;
    // Not two empty outputs agreeing: one line per record (and the index line).
    const auto lines = static_cast<std::size_t>(std::count(theirs.begin(), theirs.end(), '\n'));
    EXPECT_EQ(lines, records.size() + (std::string(name) == "py-indexed.log" ? 2 : 0)) << name;
  }
  // And it refuses what LogReader refuses (it is a checker, not a printer of anything).
  std::string cut = ReadBytes(dir / "py.log");
  WriteBytes(dir / "py-cut.log", cut.substr(0, cut.size() - 3));
  int status = 0;
  Capture(kSystemPython + " " + kPythonReader + " " + (dir / "py-cut.log").string() + " 2>/dev/null", status);
  EXPECT_NE(status, 0);
}

// ---------------------------------------------------------------------------------------------
// Damaged files.

// The error a file cut after `cut` bytes of the file holding `records` must give, or nothing
// when the cut falls between records.
struct ExpectedError {
  std::int64_t record;
  std::int64_t offset;
  std::string reason;
};

std::optional<ExpectedError> ErrorOfCut(const std::vector<LogRecord>& records, std::size_t cut) {
  if (cut == 0) return ExpectedError{0, 0, "empty file, not an SSL log file"};
  if (cut < 16) return ExpectedError{0, 0, "truncated header (size 16, " + std::to_string(cut) + " bytes left)"};
  std::size_t at = 16;
  for (std::size_t i = 0; i < records.size(); ++i) {
    const auto number = static_cast<std::int64_t>(i + 1);
    const auto offset = static_cast<std::int64_t>(at);
    if (cut == at) return std::nullopt;
    if (cut < at + 16) {
      return ExpectedError{number, offset,
                           "truncated record header (size 16, " + std::to_string(cut - at) + " bytes left)"};
    }
    const std::size_t size = records[i].payload.size();
    if (cut < at + 16 + size) {
      return ExpectedError{
          number, offset,
          "truncated payload (size " + std::to_string(size) + ", " + std::to_string(cut - at - 16) + " bytes left)"};
    }
    at += 16 + size;
  }
  return std::nullopt;
}

std::string Where(const fs::path& file, const ExpectedError& e) {
  return file.string() + (e.record == 0
                              ? ": header at byte 0: "
                              : ": record " + std::to_string(e.record) + " at byte " + std::to_string(e.offset) + ": ");
}

TEST(SslLogFormatError, ACutFileNamesTheRecordAndItsOffsetWhereverItIsCut) {
  const fs::path dir = TempDir();
  const std::vector<LogRecord> records = {{1, 4, "first"}, {2, 3, ""}, {3, 5, std::string(40, 'x')}, {4, 1002, "last"}};
  WriteLog(dir / "whole.log", records);
  const std::string bytes = ReadBytes(dir / "whole.log");
  const fs::path cut_file = dir / "cut.log";
  for (std::size_t cut = 0; cut < bytes.size(); ++cut) {
    WriteBytes(cut_file, bytes.substr(0, cut));
    const std::optional<ExpectedError> expected = ErrorOfCut(records, cut);
    std::vector<LogRecord> read;
    try {
      LogReader reader(cut_file.string());
      while (auto r = reader.Next()) read.push_back(*r);
      EXPECT_FALSE(expected) << "cut at " << cut << ": no error; expected " << expected->reason;
      // Cut between records: the records before the cut, unchanged.
      ExpectSameRecords(read, std::vector<LogRecord>(records.begin(), records.begin() + read.size()));
    } catch (const LogFormatError& e) {
      ASSERT_TRUE(expected) << "cut at " << cut << ": " << e.what();
      EXPECT_EQ(e.what(), Where(cut_file, *expected) + expected->reason) << "cut at " << cut;
      EXPECT_EQ(e.file, cut_file.string());
      EXPECT_EQ(e.record_number, expected->record);
      EXPECT_EQ(e.byte_offset, expected->offset);
      // Every record before the damaged one was read, unchanged.
      if (expected->record > 0) {
        ExpectSameRecords(read, std::vector<LogRecord>(records.begin(), records.begin() + (expected->record - 1)));
      }
    }
  }
}

TEST(SslLogFormatError, ACutGzipFileNamesTheRecordItEndsIn) {
  const fs::path dir = TempDir();
  const auto records = SampleRecords();
  WriteLog(dir / "whole.log.gz", records);
  const std::string bytes = ReadBytes(dir / "whole.log.gz");
  const fs::path cut_file = dir / "cut.log.gz";
  for (std::size_t cut : {std::size_t{30}, bytes.size() / 10, bytes.size() / 2, bytes.size() * 9 / 10,
                          bytes.size() - 20, bytes.size() - 1}) {
    WriteBytes(cut_file, bytes.substr(0, cut));
    std::vector<LogRecord> read;
    std::vector<std::int64_t> offsets;
    try {
      LogReader reader(cut_file.string());
      while (auto r = reader.Next()) {
        read.push_back(*r);
        offsets.push_back(reader.RecordOffset());
      }
      FAIL() << "cut at " << cut << " of " << bytes.size() << ": no error";
    } catch (const LogFormatError& e) {
      // The records before the damaged one are whole; the error names the next, at its offset.
      // (Cut before the 16 bytes of the header are inflated: the header is named.)
      ExpectSameRecords(read, std::vector<LogRecord>(records.begin(), records.begin() + read.size()));
      const bool in_header = e.record_number == 0;
      EXPECT_EQ(e.record_number, in_header && read.empty() ? 0 : static_cast<std::int64_t>(read.size() + 1))
          << e.what();
      std::int64_t offset = in_header ? 0 : 16;
      for (const LogRecord& r : read) offset += 16 + static_cast<std::int64_t>(r.payload.size());
      EXPECT_EQ(e.byte_offset, offset) << e.what();
      EXPECT_NE(std::string(e.what()).find("the gzip data is cut off too"), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find(": truncated "), std::string::npos) << e.what();
    }
  }
}

TEST(SslLogFormatError, ForeignHeadersVersionsAndSizesAreRefused) {
  const fs::path dir = TempDir();
  const fs::path file = dir / "bad.log";
  const auto expect_error = [&](const std::string& bytes, std::int64_t record, std::int64_t offset,
                                const std::string& message) {
    WriteBytes(file, bytes);
    try {
      LogReader reader(file.string());
      while (reader.Next()) {
      }
      ADD_FAILURE() << "no error for " << message;
    } catch (const LogFormatError& e) {
      EXPECT_EQ(e.what(), file.string() + ": " + message);
      EXPECT_EQ(e.record_number, record) << message;
      EXPECT_EQ(e.byte_offset, offset) << message;
    }
  };
  const std::string header("SSL_LOG_FILE\0\0\0\1", 16);
  expect_error("name: div-b\nrobots: []\n", 0, 0,
               "header at byte 0: not an SSL log file: it begins with \"name: div-b\\x0a\", not \"SSL_LOG_FILE\"");
  expect_error("SSL_LOG", 0, 0, "header at byte 0: truncated header (size 16, 7 bytes left)");
  expect_error(std::string("SSL_LOG_FILE\0\0\0\2", 16), 0, 12,
               "header at byte 12: format version 2; only version 1 is read");
  expect_error(std::string("SSL_LOG_FILE\0\0\0\0", 16), 0, 12,
               "header at byte 12: format version 0; only version 1 is read");
  // A record after a good one: its header says -1 bytes.
  const std::string good = std::string(
      "\0\0\0\0\0\0\0\1"
      "\0\0\0\4"
      "\0\0\0\2"
      "ok",
      18);
  expect_error(header + good +
                   std::string("\0\0\0\0\0\0\0\2"
                               "\0\0\0\4"
                               "\xff\xff\xff\xff",
                               16),
               2, 34, "record 2 at byte 34: negative payload size -1");
  expect_error(header + good +
                   std::string("\0\0\0\0\0\0\0\2"
                               "\0\0\0\4"
                               "\x10\0\0\0",
                               16),
               2, 34,
               "record 2 at byte 34: implausible payload size 268435456 (more than 64 MiB): the file is damaged");
  // Damaged gzip: a byte in the middle of the compressed data changed.
  WriteLog(dir / "ok.log.gz", SampleRecords());
  std::string gz = ReadBytes(dir / "ok.log.gz");
  gz[gz.size() / 2] = static_cast<char>(gz[gz.size() / 2] ^ 0x55);
  WriteBytes(file, gz);
  try {
    LogReader reader(file.string());
    while (reader.Next()) {
    }
    FAIL() << "read damaged gzip data";
  } catch (const LogFormatError& e) {
    EXPECT_NE(std::string(e.what()).find("damaged gzip data"), std::string::npos) << e.what();
    EXPECT_GE(e.record_number, 1);
  }
}

TEST(SslLogFormatError, NextThrowsTheSameErrorAgain) {
  const fs::path file = TempDir() / "again.log";
  WriteBytes(file, std::string("SSL_LOG_FILE\0\0\0\1"
                               "\0\0\0\0\0\0\0\1"
                               "\0\0\0\4"
                               "\0\0\0\x09"
                               "abc",
                               35));
  LogReader reader(file.string());
  std::string first, second;
  try {
    reader.Next();
  } catch (const LogFormatError& e) {
    first = e.what();
  }
  try {
    reader.Next();
  } catch (const LogFormatError& e) {
    second = e.what();
  }
  EXPECT_EQ(first, file.string() + ": record 1 at byte 16: truncated payload (size 9, 3 bytes left)");
  EXPECT_EQ(second, first);
}

// ---------------------------------------------------------------------------------------------
// Seek: back to a record read before (how `ubersim replay --viewer --send` jumps).

TEST(SslLogSeek, GoesBackAndAheadToARecordInPlainAndGzipFiles) {
  for (const char* name : {"seek.log", "seek.log.gz"}) {
    const fs::path file = TempDir() / name;
    const auto records = SampleRecords();
    WriteLog(file, records);
    std::vector<std::int64_t> offsets;
    ReadLog(file, &offsets);
    LogReader reader(file.string());
    // Every record, in an order that jumps back and ahead: each read whole with its number.
    for (const std::size_t i : {std::size_t{6}, std::size_t{2}, std::size_t{8}, std::size_t{0}, std::size_t{7},
                                std::size_t{7}, std::size_t{3}}) {
      reader.Seek(offsets[i], static_cast<std::int64_t>(i));
      const auto r = reader.Next();
      ASSERT_TRUE(r) << name << " record " << i + 1;
      EXPECT_EQ(r->timestamp_ns, records[i].timestamp_ns) << name << " record " << i + 1;
      EXPECT_TRUE(r->payload == records[i].payload) << name << " record " << i + 1;
      EXPECT_EQ(reader.RecordOffset(), offsets[i]);
      EXPECT_EQ(reader.Records(), static_cast<std::int64_t>(i + 1));
    }
    // Read on to the end from there.
    reader.Seek(offsets[5], 5);
    std::vector<LogRecord> rest;
    while (auto r = reader.Next()) rest.push_back(*r);
    ExpectSameRecords(rest, std::vector<LogRecord>(records.begin() + 5, records.end()));
    EXPECT_THROW(reader.Seek(3, 0), std::invalid_argument) << name;
  }
}

TEST(SslLogSeek, ForgetsAnErrorAndSeesItAgainThere) {
  for (const char* name : {"seek-cut.log", "seek-cut.log.gz"}) {
    const fs::path whole = TempDir() / (std::string("whole-") + name);
    const auto records = SampleRecords();
    WriteLog(whole, records);
    std::vector<std::int64_t> offsets;
    ReadLog(whole, &offsets);
    // Cut inside the last record's payload (the gzip cut just before its end: the data is cut off).
    const std::string bytes = ReadBytes(whole);
    const fs::path file = TempDir() / name;
    WriteBytes(file, bytes.substr(0, std::string(name).ends_with(".gz") ? bytes.size() - 12 : bytes.size() - 2));
    LogReader reader(file.string());
    std::string first;
    try {
      while (reader.Next()) {
      }
    } catch (const LogFormatError& e) {
      first = e.what();
    }
    ASSERT_FALSE(first.empty()) << name;
    reader.Seek(offsets[1], 1);
    const auto r = reader.Next();
    ASSERT_TRUE(r) << name;
    EXPECT_EQ(r->payload, records[1].payload);
    std::string again;
    try {
      while (reader.Next()) {
      }
    } catch (const LogFormatError& e) {
      again = e.what();
    }
    EXPECT_EQ(again, first) << name;
    if (std::string(name).ends_with(".gz")) {
      // A gzip seek decompresses to the offset: past the end of the data, it names that record.
      try {
        reader.Seek(static_cast<std::int64_t>(bytes.size()) * 100, 42);
        FAIL() << "no error";
      } catch (const LogFormatError& e) {
        EXPECT_EQ(e.record_number, 43);
        EXPECT_EQ(e.byte_offset, static_cast<std::int64_t>(bytes.size()) * 100);
      }
    }
  }
}

// ---------------------------------------------------------------------------------------------
// `ubersim replay`, as a user runs it, on loopback only.

// Ports of this test only (4xxxx, not the league's), one set per test so parallel runs keep apart.
std::string PortFlags(int base) {
  return " --vision-port " + std::to_string(base + 6) + " --tracker-port " + std::to_string(base + 10) +
         " --referee-port " + std::to_string(base + 3) + " --vision-legacy-port " + std::to_string(base + 5);
}

std::vector<std::string> PayloadsOfType(const std::vector<LogRecord>& records, std::int32_t type) {
  std::vector<std::string> out;
  for (const LogRecord& r : records) {
    if (r.type == type) out.push_back(r.payload);
  }
  return out;
}

// Many small frames of every type between the sample records, for order to mean something.
std::vector<LogRecord> ReplayRecords() {
  std::vector<LogRecord> records = SampleRecords();
  records.erase(records.begin() + 7);  // the 100 kB payload: bigger than a datagram can be
  const std::int64_t t = records.back().timestamp_ns;
  const std::int32_t types[] = {4, 4, 5, 3, 4, 2, 0, 1, 1002};
  for (int i = 0; i < 90; ++i) {
    records.push_back({t + i * 1000, types[i % 9], "frame " + std::to_string(i) + std::string(i * 50, 'a' + i % 26)});
  }
  return records;
}

TEST(ReplayCli, SendsEveryRecordsPayloadUnchangedInOrderToItsPort) {
  const fs::path file = TempDir() / "replay.log";
  const auto records = ReplayRecords();
  WriteLog(file, records, {.write_index = true});
  const int base = 41000;
  Receiver vision(base + 6, {"224.5.23.2"}), tracker(base + 10, {"224.5.23.2"}), referee(base + 3, {"224.5.23.1"}),
      legacy(base + 5, {"224.5.23.2"});
  ASSERT_TRUE(vision.Ok() && tracker.Ok() && referee.Ok() && legacy.Ok()) << "cannot bind the test's ports";

  auto run = std::async(std::launch::async, [&] {
    return RunUbersim("replay " + file.string() + " --local-only --speed 0" + PortFlags(base));
  });
  const auto until = std::chrono::steady_clock::now() + std::chrono::seconds(20);
  const auto want_vision = PayloadsOfType(records, 4), want_tracker = PayloadsOfType(records, 5),
             want_referee = PayloadsOfType(records, 3), want_legacy = PayloadsOfType(records, 2);
  const auto got_vision = vision.Receive(want_vision.size(), until);
  const auto got_tracker = tracker.Receive(want_tracker.size(), until);
  const auto got_referee = referee.Receive(want_referee.size(), until);
  const auto got_legacy = legacy.Receive(want_legacy.size(), until);
  const CliResult r = run.get();
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_TRUE(got_vision == want_vision) << got_vision.size() << " of " << want_vision.size() << " vision datagrams";
  EXPECT_TRUE(got_tracker == want_tracker) << got_tracker.size() << " of " << want_tracker.size();
  EXPECT_TRUE(got_referee == want_referee) << got_referee.size() << " of " << want_referee.size();
  EXPECT_TRUE(got_legacy == want_legacy) << got_legacy.size() << " of " << want_legacy.size();
  // Nothing more than that (the index, blank and unknown records are not sent).
  EXPECT_TRUE(vision.Receive(1, std::chrono::steady_clock::now()).empty());
  const std::size_t sent = want_vision.size() + want_tracker.size() + want_referee.size() + want_legacy.size();
  EXPECT_NE(r.output.find("vision (type 4): udp multicast 224.5.23.2:41006 via lo 127.0.0.1 (local only)"),
            std::string::npos)
      << r.output;
  EXPECT_NE(r.output.find("sent " + std::to_string(sent) + " datagrams"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("skipped 1 SSL_INDEX_2021 record\n"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("skipped 11 BLANK records"), std::string::npos) << r.output;
}

TEST(ReplayCli, OnePortForAllKeepsTheFilesOrder) {
  const fs::path file = TempDir() / "order.log.gz";
  const auto records = ReplayRecords();
  WriteLog(file, records);
  const int port = 41120;
  Receiver all(static_cast<std::uint16_t>(port), {"224.5.23.2", "224.5.23.1"});
  ASSERT_TRUE(all.Ok());
  std::vector<std::string> want;
  for (const LogRecord& rec : records) {
    if (rec.type >= 2 && rec.type <= 5) want.push_back(rec.payload);
  }
  const std::string p = std::to_string(port);
  auto run = std::async(std::launch::async, [&] {
    return RunUbersim("replay " + file.string() + " --local-only --speed 0 --vision-port " + p + " --tracker-port " +
                      p + " --referee-port " + p + " --vision-legacy-port " + p);
  });
  const auto got = all.Receive(want.size(), std::chrono::steady_clock::now() + std::chrono::seconds(20));
  const CliResult r = run.get();
  ASSERT_EQ(r.exit_code, 0) << r.output;
  ASSERT_EQ(got.size(), want.size());
  for (std::size_t i = 0; i < want.size(); ++i) EXPECT_TRUE(got[i] == want[i]) << "datagram " << i;
}

TEST(ReplayCli, PacesByTheRecordedTimesOverTheSpeed) {
  const fs::path file = TempDir() / "paced.log";
  // Four frames 100 ms apart (recorded time), played at speed 1 and at speed 2.
  std::vector<LogRecord> records;
  for (int i = 0; i < 4; ++i) records.push_back({1'000'000'000 + i * 100'000'000LL, 4, "f" + std::to_string(i)});
  WriteLog(file, records);
  for (const double speed : {1.0, 2.0}) {
    const int port = speed == 1.0 ? 41206 : 41216;
    Receiver vision(static_cast<std::uint16_t>(port), {"224.5.23.2"});
    ASSERT_TRUE(vision.Ok());
    auto run = std::async(std::launch::async, [&] {
      return RunUbersim("replay " + file.string() + " --local-only --speed " + std::to_string(speed) +
                        " --vision-port " + std::to_string(port));
    });
    const auto got = vision.Receive(4, std::chrono::steady_clock::now() + std::chrono::seconds(20));
    const CliResult r = run.get();
    ASSERT_EQ(r.exit_code, 0) << r.output;
    ASSERT_EQ(got.size(), 4u);
    // Never early (a loaded machine may make it late, not early): 300 ms of recording over the speed.
    const double spread = std::chrono::duration<double>(vision.Times().back() - vision.Times().front()).count();
    EXPECT_GE(spread, 0.3 / speed - 0.02) << "speed " << speed;
    EXPECT_LT(spread, 0.3 / speed + 1.0) << "speed " << speed;
  }
}

TEST(ReplayCli, LoopStartsAgainUntilInterrupted) {
  const fs::path file = TempDir() / "loop.log";
  std::vector<LogRecord> records;
  for (int i = 0; i < 3; ++i) records.push_back({i * 100'000'000LL, 4, "loop " + std::to_string(i)});
  WriteLog(file, records);
  Receiver vision(41506, {"224.5.23.2"});
  ASSERT_TRUE(vision.Ok());
  // 0.2 s a pass: SIGINT after 1.5 s ends the seventh or eighth pass, and the summary is printed.
  auto run = std::async(std::launch::async, [&] {
    return RunUbersim("replay " + file.string() + " --local-only --loop --vision-port 41506", "timeout -s INT 1.5");
  });
  const auto got = vision.Receive(9, std::chrono::steady_clock::now() + std::chrono::seconds(20));
  const CliResult r = run.get();
  EXPECT_EQ(r.exit_code, 124) << r.output;  // timeout's code: it sent the signal
  EXPECT_EQ(r.signal, 0) << r.output;       // ubersim ended itself
  ASSERT_EQ(got.size(), 9u);
  for (std::size_t i = 0; i < got.size(); ++i) EXPECT_EQ(got[i], records[i % 3].payload) << i;
  EXPECT_NE(r.output.find("passes\n"), std::string::npos) << r.output;
}

TEST(ReplayCli, InfoSummarisesTheFile) {
  const fs::path file = TempDir() / "info.log";
  const auto records = ReplayRecords();
  WriteLog(file, records, {.write_index = true});
  const CliResult r = RunUbersim("replay " + file.string() + " --info");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const std::size_t total = records.size() + 1;
  EXPECT_NE(r.output.find("file:       " + file.string() + "\n"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("records:    " + std::to_string(total) + "\n"), std::string::npos) << r.output;
  std::ostringstream vision_line;
  vision_line << "  SSL_VISION_2014 (4)          " << std::setw(10) << PayloadsOfType(records, 4).size() << "\n";
  EXPECT_NE(r.output.find(vision_line.str()), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("  type 1002 (1002)"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("  SSL_INDEX_2021 (6)                    1\n"), std::string::npos) << r.output;
  // First and last: the records' times (the index's 0 left out), in ns and UTC.
  EXPECT_NE(r.output.find("first:      1700000000123456789 ns (2023-11-14 22:13:20.123 UTC)\n"), std::string::npos)
      << r.output;
  const std::int64_t last = records.back().timestamp_ns;
  EXPECT_NE(r.output.find("last:       " + std::to_string(last) + " ns"), std::string::npos) << r.output;
  char duration[40];
  std::snprintf(duration, sizeof duration, "duration:   %.3f s\n",
                static_cast<double>(last - records.front().timestamp_ns) / 1e9);
  EXPECT_NE(r.output.find(duration), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("index:      " + std::to_string(records.size()) + " record offsets\n"), std::string::npos)
      << r.output;
  // gzip says so.
  WriteLog(TempDir() / "info.log.gz", records);
  const CliResult gz = RunUbersim("replay " + (TempDir() / "info.log.gz").string() + " --info");
  EXPECT_EQ(gz.exit_code, 0) << gz.output;
  EXPECT_NE(gz.output.find("info.log.gz (gzip)\n"), std::string::npos) << gz.output;
}

TEST(ReplayCli, ADamagedFileIsOneLineNamingTheRecordAndItsOffset) {
  const fs::path dir = TempDir();
  const std::vector<LogRecord> records = {{1, 4, "first"}, {2, 4, "second"}, {3, 4, "the third, cut"}};
  WriteLog(dir / "whole.log", records);
  const std::string bytes = ReadBytes(dir / "whole.log");
  const fs::path file = dir / "cut.log";
  WriteBytes(file, bytes.substr(0, bytes.size() - 5));
  const std::string line =
      "ubersim replay: " + file.string() + ": record 3 at byte 59: truncated payload (size 14, 9 bytes left)\n";

  Receiver vision(41306, {"224.5.23.2"});
  ASSERT_TRUE(vision.Ok());
  auto run = std::async(std::launch::async, [&] {
    return RunUbersim("replay " + file.string() + " --local-only --speed 0 --vision-port 41306");
  });
  const auto got = vision.Receive(2, std::chrono::steady_clock::now() + std::chrono::seconds(20));
  const CliResult r = run.get();
  EXPECT_TRUE(vision.Receive(1, std::chrono::steady_clock::now()).empty()) << "sent part of the cut record";
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_NE(r.output.find(line), std::string::npos) << r.output;
  // The records before it were sent.
  EXPECT_EQ(got, (std::vector<std::string>{"first", "second"}));

  const CliResult info = RunUbersim("replay " + file.string() + " --info");
  EXPECT_EQ(info.exit_code, 1) << info.output;
  EXPECT_NE(info.output.find(line), std::string::npos) << info.output;
  EXPECT_NE(info.output.find("records:    2\n"), std::string::npos) << info.output;
}

TEST(ReplayCli, MissingOrForeignFilesAndBadUsage) {
  const fs::path missing = TempDir() / "no-such.log";
  const CliResult m = RunUbersim("replay " + missing.string() + " --local-only");
  EXPECT_EQ(m.exit_code, 1) << m.output;
  EXPECT_EQ(m.output, "ubersim replay: cannot open SSL log file " + missing.string() + ": No such file or directory\n");

  const std::string world = UBERSIM_SOURCE_DIR "/models/worlds/div-b.yaml";
  const CliResult foreign = RunUbersim("replay " + world + " --info");
  EXPECT_EQ(foreign.exit_code, 1) << foreign.output;
  EXPECT_NE(foreign.output.find("ubersim replay: " + world + ": header at byte 0: not an SSL log file"),
            std::string::npos)
      << foreign.output;

  const CliResult no_file = RunUbersim("replay --local-only");
  EXPECT_EQ(no_file.exit_code, 2) << no_file.output;
  EXPECT_NE(no_file.output.find("name the log file"), std::string::npos) << no_file.output;
  const CliResult speed = RunUbersim("replay " + missing.string() + " --speed -1");
  EXPECT_EQ(speed.exit_code, 2) << speed.output;
  EXPECT_NE(speed.output.find("--speed -1: must be 0"), std::string::npos) << speed.output;
  const CliResult port = RunUbersim("replay " + missing.string() + " --vision-port 70000");
  EXPECT_EQ(port.exit_code, 2) << port.output;

  const CliResult help = RunUbersim("--help");
  EXPECT_NE(help.output.find("replay FILE"), std::string::npos) << help.output;
  const CliResult replay_help = RunUbersim("replay --help");
  EXPECT_EQ(replay_help.exit_code, 0);
  EXPECT_NE(replay_help.output.find("usage: ubersim replay FILE"), std::string::npos) << replay_help.output;
}

}  // namespace
