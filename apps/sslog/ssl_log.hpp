// SPDX-License-Identifier: Apache-2.0
// The league's SSL log file format (docs/log-files.md): a 16-byte header ("SSL_LOG_FILE", int32
// version 1), then records of an int64 receive time [Unix ns], an int32 message type, an int32
// payload size and the payload (one UDP datagram, unchanged); every integer big-endian. A file
// whose name ends in ".gz" is the gzip of that whole stream. Read by `ubersim replay`.
#pragma once

#include <cstdint>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

namespace ubersim::sslog {

/// The message types of a record; other ids (a team's private ones) are legal and skipped by size.
enum class MessageType : std::int32_t {
  kBlank = 0,        ///< BLANK: ignore
  kUnknown = 1,      ///< UNKNOWN: the recorder did not know
  kVision2010 = 2,   ///< SSL_VISION_2010: legacy vision wrapper (224.5.23.2:10005)
  kReferee2013 = 3,  ///< SSL_REFBOX_2013: Referee (224.5.23.1:10003)
  kVision2014 = 4,   ///< SSL_VISION_2014: SSL_WrapperPacket (224.5.23.2:10006)
  kTracker2020 = 5,  ///< SSL_VISION_TRACKER_2020: TrackerWrapperPacket (224.5.23.2:10010)
  kIndex2021 = 6,    ///< SSL_INDEX_2021: the optional index, the last record (IndexPayload)
};

/// The league's name of type id `type` ("SSL_VISION_2014"), or "type 1002" for an id it has none for.
std::string MessageTypeName(std::int32_t type);

inline constexpr std::string_view kFileMagic = "SSL_LOG_FILE";  ///< the file's first 12 bytes
inline constexpr std::int32_t kFormatVersion = 1;               ///< the only version written and read
inline constexpr std::int64_t kHeaderSize = 16;                 ///< magic + version; the first record's offset
inline constexpr std::int64_t kRecordHeaderSize = 16;           ///< timestamp + type + size
/// Largest payload read or written: a datagram is at most 64 KiB, so a bigger size means a damaged file.
inline constexpr std::int32_t kMaxPayloadSize = 64 * 1024 * 1024;

/// One record: when it was received, what it is, the datagram.
struct LogRecord {
  std::int64_t timestamp_ns = 0;  ///< receive time, Unix ns
  std::int32_t type = 0;          ///< a MessageType id, or another (skipped by readers that do not know it)
  std::string payload;            ///< the datagram's bytes
};

/// The payload of an index record (type 6) for records at `offsets` (file offsets; the first is 16):
/// the offsets, the index record's own length (16 + 8·N + 15) and "INDEXED", all int64 big-endian.
std::string IndexPayload(const std::vector<std::int64_t>& offsets);

/// The offsets in an index record's payload; nullopt when it is not a well-formed index
/// (its size is not 8·N + 15, its length field is not 16 + 8·N + 15, or it does not end in "INDEXED").
std::optional<std::vector<std::int64_t>> ParseIndexPayload(std::string_view payload);

/// What LogWriter writes besides the records.
struct LogWriterOptions {
  /// Close appends an index record (type 6) listing every record's offset, as ssl-log-indexer
  /// does. Only for uncompressed files: an index is for random access, which gzip does not allow.
  bool write_index = false;
};

/// Writes an SSL log file: gzip when the name ends in ".gz", the header at once, a record per
/// Write. Closed (and flushed) by Close or the destructor. Errors throw std::runtime_error naming
/// the file and the system's reason.
class LogWriter {
 public:
  /// Creates (or truncates) `path` and writes the header; throws when it cannot, or when
  /// `options.write_index` is asked for a ".gz" file.
  explicit LogWriter(const std::string& path, const LogWriterOptions& options = {});
  /// Closes the file; an error there is lost (call Close to see it).
  ~LogWriter();
  LogWriter(const LogWriter&) = delete;
  LogWriter& operator=(const LogWriter&) = delete;

  /// Appends a record. A timestamp below the last one written is raised to it: players such as
  /// ssl-log-player pace playback by the differences of timestamps, and a step back would make them
  /// wait or stall. Throws for a payload larger than kMaxPayloadSize and after Close.
  void Write(std::int64_t timestamp_ns, std::int32_t type, std::string_view payload);
  /// Write with a known type.
  void Write(std::int64_t timestamp_ns, MessageType type, std::string_view payload);
  /// Appends the index (when asked for), flushes and closes; the file is complete when it returns.
  /// Later calls do nothing.
  void Close();

  const std::string& Path() const;         ///< the file written
  std::int64_t Records() const;            ///< records written so far, the index not counted
  std::int64_t ClampedTimestamps() const;  ///< how many timestamps Write raised to the last one

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

/// A damaged or foreign file, found by LogReader: where, and what. what() is
/// "<file>: record 12 at byte 4096: truncated payload (size 300, 120 bytes left)", or
/// "<file>: header: …" for the first 16 bytes.
class LogFormatError : public std::runtime_error {
 public:
  /// `reason` is what is wrong, without the file and position.
  LogFormatError(std::string file, std::int64_t record_number, std::int64_t byte_offset, const std::string& reason);

  std::string file;            ///< the file read
  std::int64_t record_number;  ///< 1-based; 0 for the header
  std::int64_t byte_offset;    ///< where the record (or header) begins, in the uncompressed stream
};

/// Reads an SSL log file record by record. gzip is recognised by its magic bytes (1f 8b), so a
/// ".gz" file and a misnamed one read alike. Index records (type 6) are returned like any other:
/// callers skip the types they do not use.
class LogReader {
 public:
  /// Opens `path` and checks the header; throws std::runtime_error when it cannot be opened and
  /// LogFormatError when it is not an SSL log file of version 1.
  explicit LogReader(const std::string& path);
  ~LogReader();
  LogReader(const LogReader&) = delete;
  LogReader& operator=(const LogReader&) = delete;

  /// The next record, or nullopt at the end of the file. Throws LogFormatError for a negative or
  /// implausible size (> kMaxPayloadSize), a truncated record or damaged gzip data.
  std::optional<LogRecord> Next();

  /// Goes back (or ahead) to the record that begins at `offset` of the uncompressed stream, with
  /// `records_before` records before it: a place RecordOffset() and Records() - 1 gave for a record
  /// read earlier (a checkpoint). The next Next() returns that record, numbered records_before + 1.
  /// A plain file seeks at once; gzip has no random access, so a .gz reads on from where it is to a
  /// later offset and starts again from the beginning for an earlier one (it decompresses up to
  /// `offset`). An error Next() threw is forgotten. Throws std::invalid_argument for an offset
  /// before the first record, and LogFormatError (naming that record) when a .gz ends or is
  /// damaged before `offset` (a plain file finds out at the next Next()).
  void Seek(std::int64_t offset, std::int64_t records_before);

  const std::string& Path() const;    ///< the file read
  bool Compressed() const;            ///< the file is gzip
  std::int64_t RecordOffset() const;  ///< where the record last returned begins (uncompressed stream)
  std::int64_t Records() const;       ///< records returned so far

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace ubersim::sslog
