#include "record/mcap.hpp"

#include <lz4frame.h>
#include <zstd.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <cstring>
#include <fstream>
#include <iterator>

namespace shapeform::record {
namespace {

constexpr std::uint8_t kMagic[8] = {0x89, 'M', 'C', 'A', 'P', '0', '\r', '\n'};
enum Op : std::uint8_t {
  kHeader = 0x01,
  kFooter = 0x02,
  kSchema = 0x03,
  kChannel = 0x04,
  kMessage = 0x05,
  kChunk = 0x06,
  kMessageIndex = 0x07,
  kChunkIndex = 0x08,
  kStatistics = 0x0B,
  kSummaryOffset = 0x0E,
  kDataEnd = 0x0F,
};
constexpr std::size_t kRecordHead = 9;  // opcode + u64 length
constexpr std::size_t kFooterRecord = kRecordHead + 8 + 8 + 4;
constexpr int kZstdLevel = 1;  // docs/BENCHMARKS.md, "MCAP recording: compression"

/// CRC-32 (IEEE 802.3, zlib's), slicing by 8.
struct Crc32 {
  std::array<std::array<std::uint32_t, 256>, 8> t{};
  Crc32() {
    for (std::uint32_t i = 0; i < 256; ++i) {
      std::uint32_t c = i;
      for (int k = 0; k < 8; ++k) c = (c & 1) ? 0xEDB88320u ^ (c >> 1) : c >> 1;
      t[0][i] = c;
    }
    for (std::uint32_t i = 0; i < 256; ++i)
      for (std::size_t s = 1; s < 8; ++s) t[s][i] = (t[s - 1][i] >> 8) ^ t[0][t[s - 1][i] & 0xFF];
  }
  std::uint32_t update(std::uint32_t crc, const std::uint8_t* p, std::size_t n) const {
    crc = ~crc;
    while (n >= 8) {
      const std::uint32_t lo = crc ^ (std::uint32_t(p[0]) | std::uint32_t(p[1]) << 8 |
                                      std::uint32_t(p[2]) << 16 | std::uint32_t(p[3]) << 24);
      const std::uint32_t hi = std::uint32_t(p[4]) | std::uint32_t(p[5]) << 8 | std::uint32_t(p[6]) << 16 |
                               std::uint32_t(p[7]) << 24;
      crc = t[7][lo & 0xFF] ^ t[6][(lo >> 8) & 0xFF] ^ t[5][(lo >> 16) & 0xFF] ^ t[4][lo >> 24] ^
            t[3][hi & 0xFF] ^ t[2][(hi >> 8) & 0xFF] ^ t[1][(hi >> 16) & 0xFF] ^ t[0][hi >> 24];
      p += 8;
      n -= 8;
    }
    while (n--) crc = t[0][(crc ^ *p++) & 0xFF] ^ (crc >> 8);
    return ~crc;
  }
};
const Crc32& crc_table() {
  static const Crc32 table;
  return table;
}
std::uint32_t crc32(const std::uint8_t* p, std::size_t n, std::uint32_t crc = 0) {
  return crc_table().update(crc, p, n);
}

/// `n` bytes of `v`, little-endian, at `p`.
inline void store_le(std::uint8_t* p, std::uint64_t v, int n) {
  for (int i = 0; i < n; ++i) p[i] = std::uint8_t(v >> (8 * i));
}

// ---- little-endian appends into a byte buffer (capacity reused: no allocation once grown) ----
void put_u8(std::vector<std::uint8_t>& b, std::uint8_t v) { b.push_back(v); }
void put_u16(std::vector<std::uint8_t>& b, std::uint16_t v) {
  const std::uint8_t x[2] = {std::uint8_t(v), std::uint8_t(v >> 8)};
  b.insert(b.end(), x, x + 2);
}
void put_u32(std::vector<std::uint8_t>& b, std::uint32_t v) {
  const std::uint8_t x[4] = {std::uint8_t(v), std::uint8_t(v >> 8), std::uint8_t(v >> 16),
                             std::uint8_t(v >> 24)};
  b.insert(b.end(), x, x + 4);
}
void put_u64(std::vector<std::uint8_t>& b, std::uint64_t v) {
  std::uint8_t x[8];
  for (int i = 0; i < 8; ++i) x[i] = std::uint8_t(v >> (8 * i));
  b.insert(b.end(), x, x + 8);
}
void set_u64(std::vector<std::uint8_t>& b, std::size_t at, std::uint64_t v) {
  for (int i = 0; i < 8; ++i) b[at + std::size_t(i)] = std::uint8_t(v >> (8 * i));
}
void set_u32(std::vector<std::uint8_t>& b, std::size_t at, std::uint32_t v) {
  for (int i = 0; i < 4; ++i) b[at + std::size_t(i)] = std::uint8_t(v >> (8 * i));
}
void put_bytes(std::vector<std::uint8_t>& b, const void* p, std::size_t n) {
  const auto* c = static_cast<const std::uint8_t*>(p);
  b.insert(b.end(), c, c + n);
}
void put_str(std::vector<std::uint8_t>& b, std::string_view s) {
  put_u32(b, std::uint32_t(s.size()));
  put_bytes(b, s.data(), s.size());
}
/// Starts a record: opcode and a length to be filled by end_record. Returns the length's position.
std::size_t begin_record(std::vector<std::uint8_t>& b, std::uint8_t op) {
  put_u8(b, op);
  const std::size_t at = b.size();
  put_u64(b, 0);
  return at;
}
void end_record(std::vector<std::uint8_t>& b, std::size_t at) { set_u64(b, at, b.size() - at - 8); }

void put_schema(std::vector<std::uint8_t>& b, std::uint16_t id, std::string_view name,
                std::string_view encoding, std::string_view data) {
  const auto at = begin_record(b, kSchema);
  put_u16(b, id);
  put_str(b, name);
  put_str(b, encoding);
  put_str(b, data);  // bytes: the same u32 length prefix
  end_record(b, at);
}
void put_channel(std::vector<std::uint8_t>& b, std::uint16_t id, std::uint16_t schema_id,
                 std::string_view topic, std::string_view encoding,
                 const std::map<std::string, std::string>& metadata) {
  const auto at = begin_record(b, kChannel);
  put_u16(b, id);
  put_u16(b, schema_id);
  put_str(b, topic);
  put_str(b, encoding);
  const auto map_at = b.size();
  put_u32(b, 0);
  for (const auto& [k, v] : metadata) {
    put_str(b, k);
    put_str(b, v);
  }
  set_u32(b, map_at, std::uint32_t(b.size() - map_at - 4));
  end_record(b, at);
}

}  // namespace

std::optional<McapCompression> parse_mcap_compression(std::string_view name) {
  if (name == "none") return McapCompression::None;
  if (name == "zstd") return McapCompression::Zstd;
  if (name == "lz4") return McapCompression::Lz4;
  return std::nullopt;
}

const char* to_string(McapCompression c) {
  switch (c) {
    case McapCompression::None:
      return "none";
    case McapCompression::Zstd:
      return "zstd";
    case McapCompression::Lz4:
      return "lz4";
  }
  return "none";
}

const char* mcap_chunk_compression(McapCompression c) {
  return c == McapCompression::None ? "" : to_string(c);
}

// ================================================================ writer

struct McapWriter::Codec {
  ZSTD_CCtx* zstd = nullptr;
  LZ4F_preferences_t lz4{};
  ~Codec() {
    if (zstd) ZSTD_freeCCtx(zstd);
  }
};

McapWriter::McapWriter(McapOptions o) : options_(std::move(o)), codec_(std::make_unique<Codec>()) {
  if (options_.chunk_bytes == 0) options_.chunk_bytes = 1;
}

McapWriter::~McapWriter() {
  try {
    close();
  } catch (...) {  // a destructor does not throw; close() counts its write errors
  }
}

void McapWriter::open(const std::filesystem::path& file) {
  close();
  file_ = std::fopen(file.c_str(), "wb");
  if (!file_)
    throw std::runtime_error("cannot create MCAP file " + file.string() + ": " + std::strerror(errno));
  std::setvbuf(file_, nullptr, _IOFBF, 1 << 16);
  offset_ = 0;
  write_errors_ = 0;
  message_count_ = 0;
  start_ = end_ = 0;
  for (auto& sc : schemas_) sc.chunk = 0;  // kept from before open() or a previous file, written afresh
  for (auto& ch : channels_) {
    ch.chunk = 0;
    ch.next_sequence = 0;
    ch.count = 0;
    ch.index.clear();
  }
  chunk_channels_.clear();
  chunk_indexes_.clear();
  chunk_number_ = 1;
  chunk_messages_ = 0;
  chunk_.clear();
  chunk_.reserve(options_.chunk_bytes + (1 << 12));
  put(kMagic, sizeof kMagic);
  scratch_.clear();
  const auto at = begin_record(scratch_, kHeader);
  put_str(scratch_, options_.profile);
  put_str(scratch_, options_.library);
  end_record(scratch_, at);
  put(scratch_.data(), scratch_.size());
}

std::uint16_t McapWriter::add_schema(std::string_view name, std::string_view encoding,
                                     std::string_view data) {
  if (schemas_.size() >= 0xFFFF) throw std::length_error("MCAP: more than 65535 schemas");
  schemas_.push_back(Schema{std::string(name), std::string(encoding), std::string(data), 0});
  return std::uint16_t(schemas_.size());
}

std::uint16_t McapWriter::add_channel(std::uint16_t schema_id, std::string_view topic,
                                      std::string_view message_encoding,
                                      const std::map<std::string, std::string>& metadata) {
  if (schema_id > schemas_.size())
    throw std::invalid_argument("MCAP channel " + std::string(topic) + ": unknown schema id " +
                                std::to_string(schema_id));
  if (channels_.size() >= 0xFFFF) throw std::length_error("MCAP: more than 65535 channels");
  Channel c;
  c.schema_id = schema_id;
  c.topic = topic;
  c.encoding = message_encoding;
  c.metadata = metadata;
  channels_.push_back(std::move(c));
  return std::uint16_t(channels_.size());
}

void McapWriter::write(std::uint16_t channel, std::uint64_t log_time_ns, std::uint64_t publish_time_ns,
                       const std::uint8_t* data, std::size_t size) {
  if (channel == 0 || channel > channels_.size())
    throw std::invalid_argument("MCAP write: unknown channel id " + std::to_string(channel));
  write(channel, channels_[channel - 1].next_sequence, log_time_ns, publish_time_ns, data, size);
}

void McapWriter::write(std::uint16_t channel, std::uint32_t sequence, std::uint64_t log_time_ns,
                       std::uint64_t publish_time_ns, const std::uint8_t* data, std::size_t size) {
  if (channel == 0 || channel > channels_.size())
    throw std::invalid_argument("MCAP write: unknown channel id " + std::to_string(channel));
  if (!file_) return;
  Channel& c = channels_[channel - 1];
  if (c.chunk !=
      chunk_number_) {  // first message of this channel in this chunk: its schema and channel first
    if (c.schema_id != 0) {
      Schema& s = schemas_[c.schema_id - 1];
      if (s.chunk != chunk_number_) {
        put_schema(chunk_, c.schema_id, s.name, s.encoding, s.data);
        s.chunk = chunk_number_;
      }
    }
    put_channel(chunk_, channel, c.schema_id, c.topic, c.encoding, c.metadata);
    c.chunk = chunk_number_;
    c.index.clear();
    chunk_channels_.push_back(channel);
  }
  c.index.push_back(log_time_ns);
  c.index.push_back(chunk_.size());
  // The record's 31 bytes of header built on the stack and appended at once (the hot path).
  std::uint8_t head[kRecordHead + 2 + 4 + 8 + 8];
  head[0] = kMessage;
  store_le(head + 1, std::uint64_t(2 + 4 + 8 + 8 + size), 8);
  store_le(head + 9, channel, 2);
  store_le(head + 11, sequence, 4);
  store_le(head + 15, log_time_ns, 8);
  store_le(head + 23, publish_time_ns, 8);
  chunk_.insert(chunk_.end(), head, head + sizeof head);
  chunk_.insert(chunk_.end(), data, data + size);
  c.next_sequence = sequence + 1;
  ++c.count;
  if (chunk_messages_ == 0 || log_time_ns < chunk_start_) chunk_start_ = log_time_ns;
  if (chunk_messages_ == 0 || log_time_ns > chunk_end_) chunk_end_ = log_time_ns;
  if (message_count_ == 0 || log_time_ns < start_) start_ = log_time_ns;
  if (message_count_ == 0 || log_time_ns > end_) end_ = log_time_ns;
  ++chunk_messages_;
  ++message_count_;
  if (chunk_.size() >= options_.chunk_bytes) end_chunk();
}

void McapWriter::put(const void* data, std::size_t size) {
  if (!file_ || size == 0) return;
  if (std::fwrite(data, 1, size, file_) != size) ++write_errors_;
  offset_ += size;  // the file's layout (offsets in the indexes) as written, errors or not
}

void McapWriter::compress_chunk() {
  compressed_.clear();
  switch (options_.compression) {
    case McapCompression::None:
      return;
    case McapCompression::Zstd: {
      if (!codec_->zstd) codec_->zstd = ZSTD_createCCtx();
      compressed_.resize(ZSTD_compressBound(chunk_.size()));
      const std::size_t n = ZSTD_compressCCtx(codec_->zstd, compressed_.data(), compressed_.size(),
                                              chunk_.data(), chunk_.size(), kZstdLevel);
      if (ZSTD_isError(n))
        throw std::runtime_error(std::string("zstd compression failed: ") + ZSTD_getErrorName(n));
      compressed_.resize(n);
      return;
    }
    case McapCompression::Lz4: {
      auto& prefs = codec_->lz4;
      prefs = LZ4F_preferences_t{};
      prefs.frameInfo.contentSize = chunk_.size();
      compressed_.resize(LZ4F_compressFrameBound(chunk_.size(), &prefs));
      const std::size_t n =
          LZ4F_compressFrame(compressed_.data(), compressed_.size(), chunk_.data(), chunk_.size(), &prefs);
      if (LZ4F_isError(n))
        throw std::runtime_error(std::string("lz4 compression failed: ") + LZ4F_getErrorName(n));
      compressed_.resize(n);
      return;
    }
  }
}

void McapWriter::end_chunk() {
  if (!file_ || chunk_messages_ == 0) return;
  compress_chunk();
  const bool raw = options_.compression == McapCompression::None;
  const std::uint8_t* body = raw ? chunk_.data() : compressed_.data();
  const std::size_t body_size = raw ? chunk_.size() : compressed_.size();
  const char* compression = mcap_chunk_compression(options_.compression);

  ChunkIndex ci;
  ci.start = chunk_start_;
  ci.end = chunk_end_;
  ci.offset = offset_;
  ci.compressed = body_size;
  ci.uncompressed = chunk_.size();
  scratch_.clear();
  put_u8(scratch_, kChunk);
  const std::size_t fixed = 8 + 8 + 8 + 4 + 4 + std::strlen(compression) + 8;
  put_u64(scratch_, fixed + body_size);
  put_u64(scratch_, chunk_start_);
  put_u64(scratch_, chunk_end_);
  put_u64(scratch_, chunk_.size());
  put_u32(scratch_, crc32(chunk_.data(), chunk_.size()));
  put_str(scratch_, compression);
  put_u64(scratch_, body_size);
  put(scratch_.data(), scratch_.size());
  put(body, body_size);
  ci.length = offset_ - ci.offset;

  // Message indexes, by channel id.
  std::sort(chunk_channels_.begin(), chunk_channels_.end());
  const std::uint64_t index_start = offset_;
  scratch_.clear();
  for (const auto id : chunk_channels_) {
    Channel& c = channels_[id - 1];
    ci.index_offsets.emplace_back(id, index_start + scratch_.size());
    const auto at = begin_record(scratch_, kMessageIndex);
    put_u16(scratch_, id);
    put_u32(scratch_, std::uint32_t(c.index.size() * 8));
    for (const auto v : c.index) put_u64(scratch_, v);
    end_record(scratch_, at);
    c.index.clear();
  }
  put(scratch_.data(), scratch_.size());
  ci.index_length = offset_ - index_start;
  chunk_indexes_.push_back(std::move(ci));

  chunk_.clear();
  chunk_channels_.clear();
  chunk_messages_ = 0;
  ++chunk_number_;
}

void McapWriter::flush() {
  if (!file_) return;
  end_chunk();
  if (std::fflush(file_) != 0) ++write_errors_;
}

void McapWriter::close() {
  if (!file_) return;
  end_chunk();
  scratch_.clear();
  auto at = begin_record(scratch_, kDataEnd);
  put_u32(scratch_, 0);  // data section CRC: not computed (0 = not available, as the spec allows)
  end_record(scratch_, at);
  put(scratch_.data(), scratch_.size());

  // The summary, built in memory so its CRC covers it and the footer's first fields.
  const std::uint64_t summary_start = offset_;
  std::vector<std::uint8_t>& s = scratch_;
  s.clear();
  struct Group {
    std::uint8_t op;
    std::uint64_t start, length;
  };
  std::vector<Group> groups;
  auto group = [&](std::uint8_t op, std::size_t from) {
    if (s.size() > from) groups.push_back(Group{op, summary_start + from, s.size() - from});
  };
  std::size_t from = s.size();
  for (std::size_t i = 0; i < schemas_.size(); ++i)
    put_schema(s, std::uint16_t(i + 1), schemas_[i].name, schemas_[i].encoding, schemas_[i].data);
  group(kSchema, from);
  from = s.size();
  for (std::size_t i = 0; i < channels_.size(); ++i)
    put_channel(s, std::uint16_t(i + 1), channels_[i].schema_id, channels_[i].topic, channels_[i].encoding,
                channels_[i].metadata);
  group(kChannel, from);
  from = s.size();
  at = begin_record(s, kStatistics);
  put_u64(s, message_count_);
  put_u16(s, std::uint16_t(schemas_.size()));
  put_u32(s, std::uint32_t(channels_.size()));
  put_u32(s, 0);  // attachments
  put_u32(s, 0);  // metadata
  put_u32(s, std::uint32_t(chunk_indexes_.size()));
  put_u64(s, start_);
  put_u64(s, end_);
  const auto map_at = s.size();
  put_u32(s, 0);
  for (std::size_t i = 0; i < channels_.size(); ++i) {
    put_u16(s, std::uint16_t(i + 1));
    put_u64(s, channels_[i].count);
  }
  set_u32(s, map_at, std::uint32_t(s.size() - map_at - 4));
  end_record(s, at);
  group(kStatistics, from);
  from = s.size();
  for (const auto& ci : chunk_indexes_) {
    at = begin_record(s, kChunkIndex);
    put_u64(s, ci.start);
    put_u64(s, ci.end);
    put_u64(s, ci.offset);
    put_u64(s, ci.length);
    put_u32(s, std::uint32_t(ci.index_offsets.size() * 10));
    for (const auto& [id, off] : ci.index_offsets) {
      put_u16(s, id);
      put_u64(s, off);
    }
    put_u64(s, ci.index_length);
    put_str(s, mcap_chunk_compression(options_.compression));
    put_u64(s, ci.compressed);
    put_u64(s, ci.uncompressed);
    end_record(s, at);
  }
  group(kChunkIndex, from);
  const std::uint64_t summary_offset_start = summary_start + s.size();
  for (const auto& g : groups) {
    at = begin_record(s, kSummaryOffset);
    put_u8(s, g.op);
    put_u64(s, g.start);
    put_u64(s, g.length);
    end_record(s, at);
  }
  put_u8(s, kFooter);
  put_u64(s, 8 + 8 + 4);
  put_u64(s, summary_start);
  put_u64(s, summary_offset_start);
  const std::uint32_t crc = crc32(s.data(), s.size());  // the summary through summary_offset_start
  put_u32(s, crc);
  put_bytes(s, kMagic, sizeof kMagic);
  put(s.data(), s.size());
  if (std::fclose(file_) != 0) ++write_errors_;
  file_ = nullptr;
}

// ================================================================ reader

McapError::McapError(const std::filesystem::path& file, std::uint64_t offset, const std::string& what)
    : std::runtime_error(file.string() + ": byte " + std::to_string(offset) + ": " + what), offset_(offset) {}

namespace {

/// Bounds-checked little-endian reads over [p, end); a read past the end throws Short.
struct Short {};
struct Cursor {
  const std::uint8_t* p;
  const std::uint8_t* end;
  std::size_t left() const { return std::size_t(end - p); }
  void need(std::size_t n) const {
    if (left() < n) throw Short{};
  }
  std::uint8_t u8() {
    need(1);
    return *p++;
  }
  /// An unsigned little-endian integer of T's size.
  template <class T>
  T le() {
    need(sizeof(T));
    T v = 0;
    for (int i = static_cast<int>(sizeof(T)) - 1; i >= 0; --i) v = static_cast<T>(v << 8 | p[i]);
    p += sizeof(T);
    return v;
  }
  std::uint16_t u16() { return le<std::uint16_t>(); }
  std::uint32_t u32() { return le<std::uint32_t>(); }
  std::uint64_t u64() { return le<std::uint64_t>(); }
  std::string str() {
    const std::uint32_t n = u32();
    need(n);
    std::string s(reinterpret_cast<const char*>(p), n);
    p += n;
    return s;
  }
  Cursor sub(std::uint64_t n) {
    need(n);
    Cursor c{p, p + n};
    p += n;
    return c;
  }
};

McapSchema parse_schema(Cursor c) {
  McapSchema s;
  s.id = c.u16();
  s.name = c.str();
  s.encoding = c.str();
  s.data = c.str();
  return s;
}

McapChannel parse_channel(Cursor c) {
  McapChannel ch;
  ch.id = c.u16();
  ch.schema_id = c.u16();
  ch.topic = c.str();
  ch.message_encoding = c.str();
  Cursor m = c.sub(c.u32());
  while (m.left() > 0) {
    std::string k = m.str();
    ch.metadata[std::move(k)] = m.str();
  }
  return ch;
}

McapMessage parse_message(Cursor c) {
  McapMessage m;
  m.channel = c.u16();
  m.sequence = c.u32();
  m.log_time = c.u64();
  m.publish_time = c.u64();
  m.data.assign(c.p, c.end);
  return m;
}

struct Decompressor {
  ZSTD_DCtx* zstd = nullptr;
  LZ4F_dctx* lz4 = nullptr;
  ~Decompressor() {
    if (zstd) ZSTD_freeDCtx(zstd);
    if (lz4) LZ4F_freeDecompressionContext(lz4);
  }
  /// Empty string on success, else the reason.
  std::string run(const std::string& compression, const std::uint8_t* in, std::size_t n,
                  std::vector<std::uint8_t>& out) {
    if (compression.empty()) {
      if (n != out.size())
        return "uncompressed size " + std::to_string(out.size()) + " != records size " + std::to_string(n);
      std::memcpy(out.data(), in, n);
      return "";
    }
    if (compression == "zstd") {
      if (!zstd) zstd = ZSTD_createDCtx();
      const std::size_t r = ZSTD_decompressDCtx(zstd, out.data(), out.size(), in, n);
      if (ZSTD_isError(r)) return std::string("zstd: ") + ZSTD_getErrorName(r);
      if (r != out.size())
        return "zstd: " + std::to_string(r) + " bytes, expected " + std::to_string(out.size());
      return "";
    }
    if (compression == "lz4") {
      if (!lz4 && LZ4F_isError(LZ4F_createDecompressionContext(&lz4, LZ4F_VERSION))) return "lz4: no context";
      LZ4F_resetDecompressionContext(lz4);
      std::size_t done_in = 0, done_out = 0;
      while (done_in < n) {
        std::size_t src = n - done_in, dst = out.size() - done_out;
        const std::size_t r = LZ4F_decompress(lz4, out.data() + done_out, &dst, in + done_in, &src, nullptr);
        if (LZ4F_isError(r)) return std::string("lz4: ") + LZ4F_getErrorName(r);
        done_in += src;
        done_out += dst;
        if (r == 0) break;
        if (src == 0 && dst == 0) return "lz4: frame cut short";
      }
      if (done_out != out.size())
        return "lz4: " + std::to_string(done_out) + " bytes, expected " + std::to_string(out.size());
      return "";
    }
    return "unknown compression \"" + compression + "\"";
  }
};

std::vector<std::uint8_t> read_all(const std::filesystem::path& file) {
  std::ifstream in(file, std::ios::binary);
  if (!in) throw std::runtime_error("cannot open MCAP file " + file.string() + ": " + std::strerror(errno));
  return std::vector<std::uint8_t>(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

}  // namespace

McapReader::McapReader(const std::filesystem::path& file) : path_(file) {
  const auto bytes = read_all(file);
  const std::uint8_t* base = bytes.data();
  const std::size_t size = bytes.size();
  if (size == 0) throw McapError(file, 0, "empty file, not MCAP");
  if (size < sizeof kMagic || std::memcmp(base, kMagic, sizeof kMagic) != 0)
    throw McapError(file, 0,
                    size < sizeof kMagic && std::memcmp(base, kMagic, size) == 0
                        ? "file too short for MCAP (" + std::to_string(size) + " bytes)"
                        : "not an MCAP file (no MCAP magic at its start)");
  auto at = [&](const std::uint8_t* p) { return std::uint64_t(p - base); };
  Decompressor dec;
  std::vector<std::uint8_t> records;
  std::map<std::uint16_t, McapSchema> schemas;
  std::map<std::uint16_t, McapChannel> channels;

  // Records inside a chunk: schemas, channels, messages.
  auto read_chunk = [&](Cursor c, std::uint64_t offset) {
    McapChunkInfo info;
    info.offset = offset;
    info.start_time = c.u64();
    info.end_time = c.u64();
    info.uncompressed_size = c.u64();
    const std::uint32_t crc = c.u32();
    info.compression = c.str();
    Cursor body = c.sub(c.u64());
    info.compressed_size = body.left();
    records.resize(info.uncompressed_size);
    if (const auto problem = dec.run(info.compression, body.p, body.left(), records); !problem.empty())
      throw McapError(file, offset, "chunk: " + problem);
    if (crc != 0 && crc32(records.data(), records.size()) != crc)
      throw McapError(file, offset, "chunk: CRC of its records does not match");
    Cursor r{records.data(), records.data() + records.size()};
    try {
      while (r.left() > 0) {
        const std::uint8_t op = r.u8();
        Cursor rec = r.sub(r.u64());
        if (op == kSchema) {
          auto s = parse_schema(rec);
          schemas[s.id] = std::move(s);
        } else if (op == kChannel) {
          auto ch = parse_channel(rec);
          channels[ch.id] = std::move(ch);
        } else if (op == kMessage) {
          messages_.push_back(parse_message(rec));
        }
      }
    } catch (const Short&) {
      throw McapError(file, offset, "chunk: a record inside runs past the chunk's end");
    }
    chunks_.push_back(std::move(info));
  };

  // Complete file: footer, then the summary's chunk indexes.
  bool done = false;
  if (size >= 2 * sizeof kMagic + kFooterRecord && std::memcmp(base + size - 8, kMagic, 8) == 0) {
    Cursor f{base + size - 8 - kFooterRecord, base + size - 8};
    if (f.u8() == kFooter && f.u64() == 20) {
      const std::uint64_t summary_start = f.u64();
      const std::uint64_t summary_offset_start = f.u64();
      const std::uint32_t crc = f.u32();
      const std::uint64_t footer_at = size - 8 - kFooterRecord;
      if (summary_start != 0 && summary_start <= footer_at) {
        if (crc != 0 && crc32(base + summary_start, footer_at + 1 + 8 + 16 - summary_start) != crc)
          throw McapError(file, summary_start, "summary: CRC does not match the footer's");
        const std::uint64_t summary_end = summary_offset_start != 0 ? summary_offset_start : footer_at;
        Cursor s{base + summary_start, base + std::min<std::uint64_t>(summary_end, footer_at)};
        std::vector<std::pair<std::uint64_t, std::uint64_t>> chunk_records;  // offset, length
        try {
          while (s.left() > 0) {
            const auto rec_at = at(s.p);
            const std::uint8_t op = s.u8();
            Cursor rec = s.sub(s.u64());
            if (op == kSchema) {
              auto sc = parse_schema(rec);
              schemas[sc.id] = std::move(sc);
            } else if (op == kChannel) {
              auto ch = parse_channel(rec);
              channels[ch.id] = std::move(ch);
            } else if (op == kChunkIndex) {
              rec.u64();
              rec.u64();
              const std::uint64_t off = rec.u64(), len = rec.u64();
              if (off + len > summary_start || len < kRecordHead)
                throw McapError(file, rec_at, "chunk index points outside the data section");
              chunk_records.emplace_back(off, len);
            }
          }
        } catch (const Short&) {
          throw McapError(file, at(s.p), "summary: a record runs past the summary's end");
        }
        for (const auto& [off, len] : chunk_records) {
          Cursor c{base + off, base + off + len};
          if (c.u8() != kChunk)
            throw McapError(file, off, "chunk index points at a record that is not a chunk");
          try {
            read_chunk(c.sub(c.u64()), off);
          } catch (const Short&) {
            throw McapError(file, off, "chunk record cut short");
          }
        }
        complete_ = true;
        done = true;
      }
    }
  }

  // Otherwise (no summary: killed hard, or written without one): every record from the start.
  if (!done) {
    bool in_summary = false;
    Cursor c{base + sizeof kMagic, base + size};
    while (c.left() > 0) {
      const std::uint8_t* rec_start = c.p;
      const auto offset = at(rec_start);
      std::uint8_t op = 0;
      Cursor rec{nullptr, nullptr};
      try {
        op = c.u8();
        if (op == 0) {  // zeros where a record should start: a file system's tail after a crash
          truncated_ = true;
          dropped_bytes_ = size - offset;
          break;
        }
        rec = c.sub(c.u64());
      } catch (const Short&) {
        truncated_ = true;
        dropped_bytes_ = size - offset;
        break;
      }
      try {
        if (op == kFooter) {  // only the closing magic may follow; a part of it is a cut too
          if (c.left() > 0 && (c.left() != sizeof kMagic || std::memcmp(c.p, kMagic, sizeof kMagic) != 0)) {
            truncated_ = true;
            dropped_bytes_ = c.left();
          }
          break;
        }
        if (in_summary) {
          // the summary repeats the data section's schemas and channels
        } else if (op == kHeader) {
          profile_ = rec.str();
          library_ = rec.str();
        } else if (op == kSchema) {
          auto s = parse_schema(rec);
          schemas[s.id] = std::move(s);
        } else if (op == kChannel) {
          auto ch = parse_channel(rec);
          channels[ch.id] = std::move(ch);
        } else if (op == kMessage) {
          messages_.push_back(parse_message(rec));
        } else if (op == kChunk) {
          read_chunk(rec, offset);
        } else if (op == kDataEnd) {
          in_summary = true;  // what follows (a summary, maybe cut short) repeats what was read
        }
      } catch (const Short&) {
        throw McapError(file, offset, "record (opcode " + std::to_string(op) + ") shorter than its fields");
      }
    }
  }
  if (profile_.empty() && library_.empty()) {  // the header, for a complete file too
    Cursor h{base + sizeof kMagic, base + size};
    try {
      if (h.u8() == kHeader) {
        Cursor rec = h.sub(h.u64());
        profile_ = rec.str();
        library_ = rec.str();
      }
    } catch (const Short&) {
    }
  }
  for (auto& [id, s] : schemas) schemas_.push_back(std::move(s));
  for (auto& [id, ch] : channels) channels_.push_back(std::move(ch));
  std::stable_sort(messages_.begin(), messages_.end(),
                   [](const McapMessage& a, const McapMessage& b) { return a.log_time < b.log_time; });
}

McapReader recover_mcap(const std::filesystem::path& in, const std::filesystem::path& out,
                        McapOptions options) {
  McapReader reader(in);
  rewrite_mcap(reader, out, std::move(options));
  return reader;
}

void rewrite_mcap(const McapReader& reader, const std::filesystem::path& out, McapOptions options) {
  if (options.profile.empty()) options.profile = reader.profile();
  McapWriter writer(options);
  writer.open(out);
  // The writer numbers ids from 1: the file's ids are mapped onto them.
  std::map<std::uint16_t, std::uint16_t> schema_ids, channel_ids;
  for (const auto& s : reader.schemas()) schema_ids[s.id] = writer.add_schema(s.name, s.encoding, s.data);
  for (const auto& c : reader.channels()) {
    const auto found = schema_ids.find(c.schema_id);
    const std::uint16_t sid = found == schema_ids.end() ? std::uint16_t(0) : found->second;
    channel_ids[c.id] = writer.add_channel(sid, c.topic, c.message_encoding, c.metadata);
  }
  for (const auto& m : reader.messages()) {
    const auto it = channel_ids.find(m.channel);
    if (it == channel_ids.end())
      throw std::runtime_error(reader.path().string() + ": a message on channel " +
                               std::to_string(m.channel) + ", which no channel record defines");
    writer.write(it->second, m.sequence, m.log_time, m.publish_time, m.data.data(), m.data.size());
  }
  writer.close();
  if (writer.write_errors() != 0)
    throw std::runtime_error("writing " + out.string() + " failed (" + std::to_string(writer.write_errors()) +
                             " write errors: disk full?)");
}

}  // namespace shapeform::record
