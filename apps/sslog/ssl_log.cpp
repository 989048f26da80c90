// SPDX-License-Identifier: Apache-2.0
#include "ssl_log.hpp"

#include <zlib.h>

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstring>

namespace ubersim::sslog {
namespace {

constexpr std::string_view kIndexTrailer = "INDEXED";
constexpr std::size_t kReadChunk = 64 * 1024;  // bytes read from the file at a time

void PutBigEndian(std::string& out, std::uint64_t value, int bytes) {
  for (int i = bytes - 1; i >= 0; --i) out.push_back(static_cast<char>((value >> (8 * i)) & 0xFF));
}

std::uint64_t GetBigEndian(const char* in, int bytes) {
  std::uint64_t value = 0;
  for (int i = 0; i < bytes; ++i) value = (value << 8) | static_cast<unsigned char>(in[i]);
  return value;
}

bool EndsWith(const std::string& text, std::string_view end) {
  return text.size() >= end.size() && text.compare(text.size() - end.size(), end.size(), end) == 0;
}

// The system's reason for the last failure, for a message.
std::string SystemReason() { return errno != 0 ? std::strerror(errno) : "unknown error"; }

// What zlib says went wrong with `file`: its message, or the system's when it was an I/O error.
std::string GzReason(gzFile file) {
  int code = Z_OK;
  const char* message = gzerror(file, &code);
  if (code == Z_ERRNO) return SystemReason();
  return message && *message ? message : "zlib error " + std::to_string(code);
}

// `bytes` as a C-like literal, for quoting the start of a file that is not a log.
std::string Quoted(std::string_view bytes) {
  std::string out = "\"";
  for (const char c : bytes) {
    const auto u = static_cast<unsigned char>(c);
    if (u >= 0x20 && u < 0x7F && c != '"' && c != '\\') {
      out.push_back(c);
    } else {
      char hex[5];
      std::snprintf(hex, sizeof hex, "\\x%02x", u);
      out += hex;
    }
  }
  return out + "\"";
}

std::string Position(const std::string& file, std::int64_t record, std::int64_t offset) {
  if (record == 0) return file + ": header at byte " + std::to_string(offset);
  return file + ": record " + std::to_string(record) + " at byte " + std::to_string(offset);
}

}  // namespace

std::string MessageTypeName(std::int32_t type) {
  switch (static_cast<MessageType>(type)) {
    case MessageType::kBlank:
      return "BLANK";
    case MessageType::kUnknown:
      return "UNKNOWN";
    case MessageType::kVision2010:
      return "SSL_VISION_2010";
    case MessageType::kReferee2013:
      return "SSL_REFBOX_2013";
    case MessageType::kVision2014:
      return "SSL_VISION_2014";
    case MessageType::kTracker2020:
      return "SSL_VISION_TRACKER_2020";
    case MessageType::kIndex2021:
      return "SSL_INDEX_2021";
  }
  return "type " + std::to_string(type);
}

std::string IndexPayload(const std::vector<std::int64_t>& offsets) {
  std::string out;
  for (const std::int64_t o : offsets) PutBigEndian(out, static_cast<std::uint64_t>(o), 8);
  const auto n = static_cast<std::int64_t>(offsets.size());
  PutBigEndian(out, static_cast<std::uint64_t>(kRecordHeaderSize + 8 * n + 15), 8);
  return out.append(kIndexTrailer);
}

std::optional<std::vector<std::int64_t>> ParseIndexPayload(std::string_view payload) {
  if (payload.size() < 15 || (payload.size() - 15) % 8 != 0) return std::nullopt;
  if (payload.substr(payload.size() - kIndexTrailer.size()) != kIndexTrailer) return std::nullopt;
  const std::size_t n = (payload.size() - 15) / 8;
  const auto length = static_cast<std::int64_t>(GetBigEndian(payload.data() + 8 * n, 8));
  if (length != kRecordHeaderSize + static_cast<std::int64_t>(payload.size())) return std::nullopt;
  std::vector<std::int64_t> offsets(n);
  for (std::size_t i = 0; i < n; ++i) offsets[i] = static_cast<std::int64_t>(GetBigEndian(payload.data() + 8 * i, 8));
  return offsets;
}

// ---------------------------------------------------------------------------------------------
// LogWriter: zlib's gz* functions for both kinds of file ("T": written as is, not compressed).

struct LogWriter::Impl {
  std::string path;
  LogWriterOptions options;
  gzFile file = nullptr;
  std::int64_t position = 0;  // bytes of the uncompressed stream written
  std::int64_t last_timestamp = 0;
  std::int64_t records = 0;
  std::int64_t clamped = 0;
  std::vector<std::int64_t> offsets;  // every record's, when an index is to be written

  ~Impl() {  // a constructor that throws after opening
    if (file) gzclose(file);
  }

  [[noreturn]] void Fail(const std::string& what, const std::string& reason) const {
    throw std::runtime_error("cannot " + what + " SSL log file " + path + ": " + reason);
  }

  void Put(const std::string& bytes) { Put(bytes.data(), bytes.size()); }
  void Put(const char* bytes, std::size_t size) {
    if (size == 0) return;
    if (gzwrite(file, bytes, static_cast<unsigned>(size)) != static_cast<int>(size)) Fail("write", GzReason(file));
    position += static_cast<std::int64_t>(size);
  }

  void PutRecord(std::int64_t timestamp_ns, std::int32_t type, std::string_view payload) {
    std::string head;
    PutBigEndian(head, static_cast<std::uint64_t>(timestamp_ns), 8);
    PutBigEndian(head, static_cast<std::uint32_t>(type), 4);
    PutBigEndian(head, static_cast<std::uint32_t>(payload.size()), 4);
    Put(head);
    Put(payload.data(), payload.size());
  }
};

LogWriter::LogWriter(const std::string& path, const LogWriterOptions& options) : impl_(std::make_unique<Impl>()) {
  Impl& w = *impl_;
  w.path = path;
  w.options = options;
  const bool gzip = EndsWith(path, ".gz");
  if (gzip && options.write_index) w.Fail("write", "an index needs an uncompressed file, and the name ends in .gz");
  errno = 0;
  w.file = gzopen(path.c_str(), gzip ? "wb" : "wbT");
  if (!w.file) w.Fail("create", SystemReason());
  std::string header(kFileMagic);
  PutBigEndian(header, static_cast<std::uint32_t>(kFormatVersion), 4);
  w.Put(header);
}

LogWriter::~LogWriter() {
  try {
    Close();
  } catch (const std::exception&) {
    // Lost, as documented: Close reports it to callers that want to know.
  }
}

void LogWriter::Write(std::int64_t timestamp_ns, std::int32_t type, std::string_view payload) {
  Impl& w = *impl_;
  if (!w.file) w.Fail("write", "it is already closed");
  if (payload.size() > static_cast<std::size_t>(kMaxPayloadSize)) {
    w.Fail("write", "a payload of " + std::to_string(payload.size()) +
                        " bytes is more than the format's readers accept (" + std::to_string(kMaxPayloadSize) + ")");
  }
  if (w.records > 0 && timestamp_ns < w.last_timestamp) {
    timestamp_ns = w.last_timestamp;
    ++w.clamped;
  }
  if (w.options.write_index) w.offsets.push_back(w.position);
  w.PutRecord(timestamp_ns, type, payload);
  w.last_timestamp = timestamp_ns;
  ++w.records;
}

void LogWriter::Write(std::int64_t timestamp_ns, MessageType type, std::string_view payload) {
  Write(timestamp_ns, static_cast<std::int32_t>(type), payload);
}

void LogWriter::Close() {
  Impl& w = *impl_;
  if (!w.file) return;
  gzFile file = w.file;
  try {
    // The index is the last record; its timestamp is 0 by definition, not raised to the last.
    if (w.options.write_index)
      w.PutRecord(0, static_cast<std::int32_t>(MessageType::kIndex2021), IndexPayload(w.offsets));
  } catch (...) {
    w.file = nullptr;
    gzclose(file);
    throw;
  }
  w.file = nullptr;
  errno = 0;
  const int status = gzclose(file);  // flushes, writes the gzip trailer, closes
  if (status != Z_OK) w.Fail("close", status == Z_ERRNO ? SystemReason() : "zlib error " + std::to_string(status));
}

const std::string& LogWriter::Path() const { return impl_->path; }
std::int64_t LogWriter::Records() const { return impl_->records; }
std::int64_t LogWriter::ClampedTimestamps() const { return impl_->clamped; }

// ---------------------------------------------------------------------------------------------
// LogFormatError

LogFormatError::LogFormatError(std::string file_name, std::int64_t record, std::int64_t offset,
                               const std::string& reason)
    : std::runtime_error(Position(file_name, record, offset) + ": " + reason),
      file(std::move(file_name)),
      record_number(record),
      byte_offset(offset) {}

// ---------------------------------------------------------------------------------------------
// LogReader: stdio for the file, zlib's inflate for gzip. Inflating here rather than through
// gzread tells exactly how many bytes a cut-off .gz still holds (gzread drops a partial read).

struct LogReader::Impl {
  std::string path;
  std::FILE* file = nullptr;
  bool gzip = false;
  z_stream zs{};           // also the input cursor of an uncompressed file (next_in, avail_in)
  bool inflating = false;  // inflateInit2 done
  bool member_end = true;  // the last gzip member ended (clean end of data if the input ends here)
  bool input_end = false;
  std::vector<unsigned char> in = std::vector<unsigned char>(kReadChunk);
  std::string error;          // why reading stopped before the end of the data, "" if it did not
  std::int64_t position = 0;  // bytes of the uncompressed stream consumed
  std::int64_t record_offset = 0;
  std::int64_t records = 0;
  std::optional<LogFormatError> failure;  // the error Next threw; thrown again by later calls

  ~Impl() {  // here, not in ~LogReader, so a constructor that throws releases them too
    if (inflating) inflateEnd(&zs);
    if (file) std::fclose(file);
  }

  // More input into `in` when it is used up; false at the end of the file (or a read error).
  bool Fill() {
    if (zs.avail_in > 0) return true;
    if (input_end) return false;
    errno = 0;
    const std::size_t got = std::fread(in.data(), 1, in.size(), file);
    if (got == 0) {
      input_end = true;
      if (std::ferror(file)) error = "read error: " + SystemReason();
      return false;
    }
    zs.next_in = in.data();
    zs.avail_in = static_cast<uInt>(got);
    return true;
  }

  // Up to `size` bytes of the uncompressed stream into `out`; fewer only at the end of the data
  // or at an error (then `error` says which).
  std::size_t Read(char* out, std::size_t size) {
    std::size_t done = 0;
    while (done < size && error.empty() && Fill()) {
      if (!gzip) {
        const std::size_t n = std::min<std::size_t>(size - done, zs.avail_in);
        std::memcpy(out + done, zs.next_in, n);
        zs.next_in += n;
        zs.avail_in -= static_cast<uInt>(n);
        done += n;
        continue;
      }
      if (member_end) {  // a new gzip member: the first, or one concatenated after the last
        inflateReset(&zs);
        member_end = false;
      }
      zs.next_out = reinterpret_cast<Bytef*>(out + done);
      zs.avail_out = static_cast<uInt>(size - done);
      const int status = inflate(&zs, Z_NO_FLUSH);
      done = size - zs.avail_out;
      if (status == Z_STREAM_END) {
        member_end = true;
      } else if (status != Z_OK && !(status == Z_BUF_ERROR && zs.avail_in == 0)) {
        error = std::string("damaged gzip data: ") + (zs.msg ? zs.msg : "zlib error " + std::to_string(status));
      }
    }
    position += static_cast<std::int64_t>(done);
    return done;
  }

  // Why a read of `size` bytes of `what` that gave `got` fell short.
  std::string ShortRead(const std::string& what, std::size_t size, std::size_t got) const {
    if (!error.empty()) return error;
    std::string reason =
        "truncated " + what + " (size " + std::to_string(size) + ", " + std::to_string(got) + " bytes left)";
    if (gzip && !member_end) reason += "; the gzip data is cut off too";
    return reason;
  }

  // Throws (and remembers, for later calls) the error of `record` at `offset`.
  [[noreturn]] void Fail(std::int64_t record, std::int64_t offset, const std::string& reason) {
    failure.emplace(path, record, offset, reason);
    throw *failure;
  }
};

LogReader::LogReader(const std::string& path) : impl_(std::make_unique<Impl>()) {
  Impl& r = *impl_;
  r.path = path;
  errno = 0;
  r.file = std::fopen(path.c_str(), "rb");
  if (!r.file) throw std::runtime_error("cannot open SSL log file " + path + ": " + SystemReason());
  // gzip by content (magic 1f 8b), so a misnamed file reads too.
  if (r.Fill() && r.zs.avail_in >= 2 && r.in[0] == 0x1F && r.in[1] == 0x8B) {
    r.gzip = true;
    if (inflateInit2(&r.zs, 15 + 16) != Z_OK)
      throw std::runtime_error("cannot read " + path + ": zlib refused to start");
    r.inflating = true;
  }
  char header[kHeaderSize];
  const std::size_t got = r.Read(header, sizeof header);
  const std::string_view start(header, std::min(got, kFileMagic.size()));
  if (!r.error.empty()) throw LogFormatError(path, 0, 0, r.error);
  if (got == 0 && !r.gzip) throw LogFormatError(path, 0, 0, "empty file, not an SSL log file");
  if (start != kFileMagic.substr(0, start.size())) {
    throw LogFormatError(path, 0, 0,
                         "not an SSL log file: it begins with " + Quoted(start) + ", not " + Quoted(kFileMagic));
  }
  if (got < sizeof header) throw LogFormatError(path, 0, 0, r.ShortRead("header", sizeof header, got));
  const auto version = static_cast<std::int32_t>(GetBigEndian(header + 12, 4));
  if (version != kFormatVersion) {
    throw LogFormatError(
        path, 0, 12,
        "format version " + std::to_string(version) + "; only version " + std::to_string(kFormatVersion) + " is read");
  }
}

LogReader::~LogReader() = default;

std::optional<LogRecord> LogReader::Next() {
  Impl& r = *impl_;
  if (r.failure) throw *r.failure;
  const std::int64_t offset = r.position;
  const std::int64_t number = r.records + 1;
  char head[kRecordHeaderSize];
  const std::size_t got = r.Read(head, sizeof head);
  if (got == 0 && r.error.empty() && (!r.gzip || r.member_end)) return std::nullopt;  // the clean end
  if (got < sizeof head) r.Fail(number, offset, r.ShortRead("record header", sizeof head, got));
  LogRecord record;
  record.timestamp_ns = static_cast<std::int64_t>(GetBigEndian(head, 8));
  record.type = static_cast<std::int32_t>(GetBigEndian(head + 8, 4));
  const auto size = static_cast<std::int32_t>(GetBigEndian(head + 12, 4));
  if (size < 0) r.Fail(number, offset, "negative payload size " + std::to_string(size));
  if (size > kMaxPayloadSize) {
    r.Fail(number, offset,
           "implausible payload size " + std::to_string(size) + " (more than 64 MiB): the file is damaged");
  }
  // Grown as the bytes arrive, so a damaged size does not allocate 64 MiB up front.
  const auto wanted = static_cast<std::size_t>(size);
  std::size_t have = 0;
  while (have < wanted) {
    const std::size_t step = std::min<std::size_t>(wanted - have, 1 << 20);
    record.payload.resize(have + step);
    const std::size_t n = r.Read(record.payload.data() + have, step);
    have += n;
    if (n < step) r.Fail(number, offset, r.ShortRead("payload", wanted, have));
  }
  r.record_offset = offset;
  r.records = number;
  return record;
}

void LogReader::Seek(std::int64_t offset, std::int64_t records_before) {
  Impl& r = *impl_;
  if (offset < kHeaderSize || records_before < 0) {
    throw std::invalid_argument("LogReader::Seek: offset " + std::to_string(offset) + " is before the first record");
  }
  r.failure.reset();
  if (!r.gzip || offset < r.position || !r.error.empty()) {
    // A plain file goes straight there; gzip starts again from the file's first byte.
    errno = 0;
    if (std::fseek(r.file, r.gzip ? 0 : static_cast<long>(offset), SEEK_SET) != 0) {
      r.Fail(records_before + 1, offset, "cannot seek: " + SystemReason());
    }
    std::clearerr(r.file);
    r.zs.next_in = r.in.data();
    r.zs.avail_in = 0;
    r.input_end = false;
    r.error.clear();
    r.member_end = true;  // the next Read starts a gzip member
    r.position = r.gzip ? 0 : offset;
  }
  // gzip: decompress up to the offset, discarding.
  std::vector<char> scratch;
  while (r.position < offset) {
    scratch.resize(static_cast<std::size_t>(std::min<std::int64_t>(offset - r.position, kReadChunk)));
    const std::size_t got = r.Read(scratch.data(), scratch.size());
    if (got < scratch.size()) {
      const std::string reason = r.error.empty() ? "the data ends before this record" : r.error;
      r.records = records_before;
      r.Fail(records_before + 1, offset, reason);
    }
  }
  r.records = records_before;
}

const std::string& LogReader::Path() const { return impl_->path; }
bool LogReader::Compressed() const { return impl_->gzip; }
std::int64_t LogReader::RecordOffset() const { return impl_->record_offset; }
std::int64_t LogReader::Records() const { return impl_->records; }

}  // namespace ubersim::sslog
