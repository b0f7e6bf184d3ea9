#pragma once
/// MCAP (https://mcap.dev/spec, version 0) written and read without a third-party MCAP library: the
/// chunked, indexed container Foxglove, Lichtblick and rosbag2 open. Pure: no DDS, no clocks (every time
/// is given by the caller, in nanoseconds), only the file named by the caller.
///
/// Layout the writer produces (docs/RECORDING.md, "run.mcap: the format"):
///   magic, Header, { Chunk(Schema*, Channel*, Message*), MessageIndex* }*, DataEnd,
///   summary (Schema*, Channel*, Statistics, ChunkIndex*), SummaryOffset*, Footer, magic.
/// Each chunk carries the schema and channel records of the channels it uses, ahead of their first
/// message, so that a file cut anywhere (a process killed hard) can be read by scanning it from the
/// start: every complete chunk is kept.
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <map>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

namespace shapeform::record {

enum class McapCompression { None, Zstd, Lz4 };

/// "none", "zstd", "lz4" -> the enum; nullopt on any other name.
std::optional<McapCompression> parse_mcap_compression(std::string_view name);
/// The enum -> "none", "zstd", "lz4" (the name parse_mcap_compression takes).
const char* to_string(McapCompression c);
/// The enum -> the chunk record's compression string: "", "zstd", "lz4".
const char* mcap_chunk_compression(McapCompression c);

struct McapOptions {
  McapCompression compression = McapCompression::Zstd;
  /// A chunk is closed once its uncompressed records reach this size (bytes).
  std::size_t chunk_bytes = 1 << 20;
  std::string profile;                ///< Header.profile ("" or e.g. "ros2")
  std::string library = "shapeform";  ///< Header.library
};

/// Writes one MCAP file. Not thread-safe: one thread writes (the recorder's). write() allocates nothing
/// once the chunk buffers have grown to their working size.
class McapWriter {
 public:
  explicit McapWriter(McapOptions o = {});
  ~McapWriter();  ///< close()
  McapWriter(const McapWriter&) = delete;
  McapWriter& operator=(const McapWriter&) = delete;

  /// Creates (truncates) `file` and writes the magic and the header (closing the file open before, if
  /// any). Schemas and channels added before, or for a previous file, are kept (their sequence numbers
  /// start again from 0). Throws std::runtime_error naming the path when it cannot be created.
  void open(const std::filesystem::path& file);
  bool is_open() const { return file_ != nullptr; }

  /// A schema (`encoding` "omgidl", "jsonschema", "ros2msg", ...; `data` its text). Ids from 1.
  std::uint16_t add_schema(std::string_view name, std::string_view encoding, std::string_view data);
  /// A channel on schema `schema_id` (0: no schema) with its message encoding ("cdr", "json"). Ids from
  /// 1. Throws std::invalid_argument on an unknown schema id.
  std::uint16_t add_channel(std::uint16_t schema_id, std::string_view topic,
                            std::string_view message_encoding,
                            const std::map<std::string, std::string>& metadata = {});

  /// One message; its sequence number is the channel's count of messages so far. A write error (disk
  /// full) is counted in write_errors(), never thrown. Throws std::invalid_argument on an unknown channel;
  /// does nothing while no file is open.
  void write(std::uint16_t channel, std::uint64_t log_time_ns, std::uint64_t publish_time_ns,
             const std::uint8_t* data, std::size_t size);
  /// The same with the sequence number given (a copy of another file keeps its numbers).
  void write(std::uint16_t channel, std::uint32_t sequence, std::uint64_t log_time_ns,
             std::uint64_t publish_time_ns, const std::uint8_t* data, std::size_t size);

  /// Ends the current chunk (the chunk and its message indexes are written) and flushes the file.
  void flush();
  /// The last chunk, DataEnd, the summary (schemas, channels, statistics, chunk indexes), the summary
  /// offsets, the footer and the closing magic. Safe to call twice, and on a writer never opened.
  void close();

  std::uint64_t messages() const { return message_count_; }
  std::uint64_t bytes_written() const { return offset_; }
  std::uint64_t write_errors() const { return write_errors_; }

 private:
  struct Schema {
    std::string name, encoding, data;
    std::uint64_t chunk = 0;  ///< the chunk (1-based count) this schema was last written into
  };
  struct Channel {
    std::uint16_t schema_id = 0;
    std::string topic, encoding;
    std::map<std::string, std::string> metadata;
    std::uint32_t next_sequence = 0;
    std::uint64_t count = 0;
    std::uint64_t chunk = 0;           ///< the chunk this channel's record was last written into
    std::vector<std::uint64_t> index;  ///< this chunk's (log_time, offset) pairs, flattened
  };
  struct ChunkIndex {
    std::uint64_t start = 0, end = 0, offset = 0, length = 0, index_length = 0, compressed = 0,
                  uncompressed = 0;
    std::vector<std::pair<std::uint16_t, std::uint64_t>> index_offsets;
  };

  void put(const void* data, std::size_t size);  ///< to the file, counting errors and offset
  void end_chunk();
  void compress_chunk();

  McapOptions options_;
  std::FILE* file_ = nullptr;
  std::uint64_t offset_ = 0;
  std::uint64_t write_errors_ = 0;
  std::uint64_t message_count_ = 0;
  std::uint64_t start_ = 0, end_ = 0;          ///< log-time range of every message written
  std::vector<Schema> schemas_;                ///< id - 1
  std::vector<Channel> channels_;              ///< id - 1
  std::vector<std::uint16_t> chunk_channels_;  ///< channels with messages in the current chunk
  std::uint64_t chunk_number_ = 1;
  std::uint64_t chunk_start_ = 0, chunk_end_ = 0, chunk_messages_ = 0;
  std::vector<std::uint8_t> chunk_;       ///< uncompressed records of the current chunk
  std::vector<std::uint8_t> compressed_;  ///< reused compression output
  std::vector<std::uint8_t> scratch_;     ///< reused record buffer (message indexes, summary)
  std::vector<ChunkIndex> chunk_indexes_;
  struct Codec;
  std::unique_ptr<Codec> codec_;
};

struct McapSchema {
  std::uint16_t id = 0;
  std::string name, encoding, data;
};
struct McapChannel {
  std::uint16_t id = 0, schema_id = 0;
  std::string topic, message_encoding;
  std::map<std::string, std::string> metadata;
};
struct McapMessage {
  std::uint16_t channel = 0;
  std::uint32_t sequence = 0;
  std::uint64_t log_time = 0, publish_time = 0;
  std::vector<std::uint8_t> data;
};
/// One chunk as the reader found it.
struct McapChunkInfo {
  std::uint64_t offset = 0;  ///< of the chunk record, from the start of the file
  std::uint64_t start_time = 0, end_time = 0;
  std::string compression;  ///< "", "zstd", "lz4"
  std::uint64_t compressed_size = 0, uncompressed_size = 0;
};

/// A file that is not MCAP or is damaged beyond a cut at its end: names the file and the byte offset.
class McapError : public std::runtime_error {
 public:
  McapError(const std::filesystem::path& file, std::uint64_t offset, const std::string& what);
  std::uint64_t offset() const { return offset_; }

 private:
  std::uint64_t offset_;
};

/// Reads a whole file: through its summary when the file is complete, else by scanning every record
/// from the start (a recording killed hard): every complete chunk is kept, a record cut short at the
/// end is dropped and reported (truncated()). Throws McapError (a file that is not MCAP, a chunk whose
/// CRC or compression is wrong) or std::runtime_error (a file that cannot be read).
class McapReader {
 public:
  explicit McapReader(const std::filesystem::path& file);

  const std::filesystem::path& path() const { return path_; }
  const std::vector<McapSchema>& schemas() const { return schemas_; }
  const std::vector<McapChannel>& channels() const { return channels_; }
  const std::vector<McapChunkInfo>& chunks() const { return chunks_; }
  const std::string& profile() const { return profile_; }
  const std::string& library() const { return library_; }
  bool complete() const { return complete_; }    ///< summary and footer found
  bool truncated() const { return truncated_; }  ///< the file ended inside a record
  /// Bytes at the end of the file that were not part of a complete record (0 unless truncated()).
  std::uint64_t dropped_bytes() const { return dropped_bytes_; }
  /// Every message, in log-time order (stable: equal times keep the file's order).
  const std::vector<McapMessage>& messages() const { return messages_; }

 private:
  std::filesystem::path path_;
  std::vector<McapSchema> schemas_;
  std::vector<McapChannel> channels_;
  std::vector<McapChunkInfo> chunks_;
  std::vector<McapMessage> messages_;
  std::string profile_, library_;
  bool complete_ = false, truncated_ = false;
  std::uint64_t dropped_bytes_ = 0;
};

/// Rewrites `in` (complete or cut short) as a complete, indexed file `out` with the same schemas,
/// channels and messages (sequence numbers and times kept), in log-time order. Returns the reader's view
/// of `in` (what was recovered). Throws as McapReader does, or std::runtime_error when `out` cannot be
/// written (or was written with errors).
McapReader recover_mcap(const std::filesystem::path& in, const std::filesystem::path& out,
                        McapOptions options = {});
/// What recover_mcap writes, from a reader already made.
void rewrite_mcap(const McapReader& reader, const std::filesystem::path& out, McapOptions options = {});

}  // namespace shapeform::record
