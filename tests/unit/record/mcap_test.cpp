// The MCAP writer and reader (common/record/mcap): round trips, many channels, files cut short.
#include "record/mcap.hpp"

#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <catch2/catch.hpp>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <new>
#include <string>
#include <vector>

#include "temp_dir.hpp"

using namespace shapeform::record;
namespace fs = std::filesystem;

// Heap allocations counted while `g_count_allocations` is set: the writer's hot path must not allocate.
namespace {
std::atomic<bool> g_count_allocations{false};
std::atomic<std::uint64_t> g_allocations{0};
}  // namespace
void* operator new(std::size_t n) {
  if (g_count_allocations.load(std::memory_order_relaxed))
    g_allocations.fetch_add(1, std::memory_order_relaxed);
  if (void* p = std::malloc(n == 0 ? 1 : n)) return p;
  throw std::bad_alloc();
}
// GCC sees the replaced operator new inlined as malloc's partner and warns about the pair it is.
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wmismatched-new-delete"
void operator delete(void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }
#pragma GCC diagnostic pop

namespace {

using shapeform::test::TempDir;

struct Written {
  std::uint16_t channel;
  std::uint32_t sequence;
  std::uint64_t log_time;
  std::vector<std::uint8_t> data;
};

std::vector<std::uint8_t> payload(std::uint64_t i) {
  std::vector<std::uint8_t> d(1 + i % 53);
  for (std::size_t k = 0; k < d.size(); ++k) d[k] = std::uint8_t(i * 31 + k * 7);
  return d;
}

void same_messages(const std::vector<McapMessage>& got, const std::vector<Written>& want) {
  REQUIRE(got.size() == want.size());
  for (std::size_t i = 0; i < got.size(); ++i) {
    INFO("message " << i);
    CHECK(got[i].channel == want[i].channel);
    CHECK(got[i].sequence == want[i].sequence);
    CHECK(got[i].log_time == want[i].log_time);
    CHECK(got[i].publish_time == want[i].log_time + 1);
    CHECK(got[i].data == want[i].data);
  }
}

std::vector<std::uint8_t> file_bytes(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  return std::vector<std::uint8_t>(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

/// Where each top-level record of a file ends (and 8, the end of the magic), walking opcode and length
/// up to the footer: the places a cut leaves nothing cut short.
std::vector<std::uint64_t> record_boundaries(const std::vector<std::uint8_t>& b) {
  std::vector<std::uint64_t> ends{8};
  std::uint64_t at = 8;
  while (at + 9 <= b.size()) {
    std::uint64_t len = 0;
    for (int i = 7; i >= 0; --i) len = len << 8 | b[at + 1 + std::size_t(i)];
    const bool footer = b[at] == 0x02;
    at += 9 + len;
    ends.push_back(at);
    if (footer) break;
  }
  return ends;
}

void write_bytes(const fs::path& p, const std::uint8_t* data, std::size_t n) {
  std::ofstream out(p, std::ios::binary | std::ios::trunc);
  out.write(reinterpret_cast<const char*>(data), std::streamsize(n));
}

}  // namespace

TEST_CASE("mcap compression names parse and print", "[mcap]") {
  for (const auto c : {McapCompression::None, McapCompression::Zstd, McapCompression::Lz4})
    CHECK(parse_mcap_compression(to_string(c)) == c);
  CHECK(std::string(mcap_chunk_compression(McapCompression::None)).empty());
  CHECK(std::string(mcap_chunk_compression(McapCompression::Lz4)) == "lz4");
  CHECK_FALSE(parse_mcap_compression("gzip"));
  CHECK_FALSE(parse_mcap_compression("ZSTD"));
  CHECK_FALSE(parse_mcap_compression(""));
}

TEST_CASE("mcap round trip with every compression", "[mcap]") {
  const auto c = GENERATE(McapCompression::None, McapCompression::Zstd, McapCompression::Lz4);
  INFO(to_string(c));
  TempDir tmp;
  const auto file = tmp.path() / "run.mcap";
  McapOptions o;
  o.compression = c;
  o.chunk_bytes = 2000;
  o.profile = "shapeform-test";
  std::vector<Written> written;
  std::uint64_t chunk_count_min = 0;
  {
    McapWriter w(o);
    CHECK_FALSE(w.is_open());
    w.open(file);
    CHECK(w.is_open());
    const auto s1 = w.add_schema("a::A", "omgidl", "module a { struct A { double x; }; };");
    const auto s2 = w.add_schema("B", "jsonschema", "{}");
    const auto c1 = w.add_channel(s1, "/a", "cdr", {{"k", "v"}, {"offered_qos", "reliable"}});
    const auto c2 = w.add_channel(s2, "/b", "json");
    const auto c3 = w.add_channel(0, "/raw", "bytes");
    std::uint32_t seq[4] = {0, 0, 0, 0};
    for (std::uint64_t i = 0; i < 500; ++i) {
      const std::uint16_t ch = i % 5 == 0 ? c2 : i % 7 == 0 ? c3 : c1;
      const auto d = payload(i);
      w.write(ch, 1000 + i, 1001 + i, d.data(), d.size());
      written.push_back({ch, seq[ch]++, 1000 + i, d});
      if (i == 250) w.flush();
    }
    CHECK(w.messages() == 500);
    CHECK(w.write_errors() == 0);
    chunk_count_min = 500 * 40 / o.chunk_bytes;
    w.close();
    w.close();  // twice: nothing more
    CHECK(w.bytes_written() == fs::file_size(file));
  }
  McapReader r(file);
  CHECK(r.complete());
  CHECK_FALSE(r.truncated());
  CHECK(r.profile() == "shapeform-test");
  CHECK(r.library() == "shapeform");
  REQUIRE(r.schemas().size() == 2);
  CHECK(r.schemas()[0].id == 1);
  CHECK(r.schemas()[0].name == "a::A");
  CHECK(r.schemas()[0].encoding == "omgidl");
  CHECK(r.schemas()[1].data == "{}");
  REQUIRE(r.channels().size() == 3);
  CHECK(r.channels()[0].topic == "/a");
  CHECK(r.channels()[0].schema_id == 1);
  CHECK(r.channels()[0].metadata ==
        std::map<std::string, std::string>{{"k", "v"}, {"offered_qos", "reliable"}});
  CHECK(r.channels()[2].schema_id == 0);
  CHECK(r.channels()[2].message_encoding == "bytes");
  CHECK(r.chunks().size() >= chunk_count_min);
  for (const auto& ch : r.chunks()) CHECK(ch.compression == mcap_chunk_compression(c));
  same_messages(r.messages(), written);
}

TEST_CASE("mcap many channels and schemas, messages out of order come back sorted and stable", "[mcap]") {
  TempDir tmp;
  const auto file = tmp.path() / "many.mcap";
  McapOptions o;
  o.chunk_bytes = 8192;
  McapWriter w(o);
  w.open(file);
  std::vector<std::uint16_t> channels;
  for (int s = 0; s < 40; ++s)
    w.add_schema("S" + std::to_string(s), "jsonschema", "{\"n\":" + std::to_string(s) + "}");
  for (int c = 0; c < 300; ++c)
    channels.push_back(w.add_channel(std::uint16_t(1 + c % 40), "/t" + std::to_string(c), "json"));
  std::vector<Written> written;
  std::vector<std::uint32_t> seq(301, 0);
  for (std::uint64_t i = 0; i < 6000; ++i) {
    const auto ch = channels[(i * 7) % channels.size()];
    const std::uint64_t t = (i * 7919) % 1000;  // out of order, with many equal times
    const auto d = payload(i);
    w.write(ch, t, t + 1, d.data(), d.size());
    written.push_back({ch, seq[ch]++, t, d});
  }
  w.close();
  std::stable_sort(written.begin(), written.end(),
                   [](const Written& a, const Written& b) { return a.log_time < b.log_time; });
  McapReader r(file);
  CHECK(r.complete());
  REQUIRE(r.schemas().size() == 40);
  REQUIRE(r.channels().size() == 300);
  CHECK(r.channels()[299].topic == "/t299");
  CHECK(r.channels()[299].schema_id == 1 + 299 % 40);
  CHECK(r.schemas()[39].data == "{\"n\":39}");
  same_messages(r.messages(), written);
}

TEST_CASE("mcap file cut anywhere keeps every complete chunk and no partial one", "[mcap]") {
  const auto c = GENERATE(McapCompression::None, McapCompression::Zstd, McapCompression::Lz4);
  INFO(to_string(c));
  TempDir tmp;
  const auto file = tmp.path() / "full.mcap";
  McapOptions o;
  o.compression = c;
  o.chunk_bytes = 1 << 20;  // chunks end at flush() only: 10 messages each
  std::vector<Written> written;
  {
    McapWriter w(o);
    w.open(file);
    const auto s = w.add_schema("S", "jsonschema", "{}");
    const auto a = w.add_channel(s, "/a", "json");
    const auto b = w.add_channel(s, "/b", "json");
    std::uint32_t seq[3] = {0, 0, 0};
    for (std::uint64_t i = 0; i < 200; ++i) {
      const std::uint16_t ch = i % 3 == 0 ? b : a;
      const auto d = payload(i);
      w.write(ch, i * 10, i * 10 + 1, d.data(), d.size());
      written.push_back({ch, seq[ch]++, i * 10, d});
      if (i % 10 == 9) w.flush();
    }
  }
  McapReader full(file);
  REQUIRE(full.chunks().size() == 20);
  std::vector<std::uint64_t> chunk_ends;  // the byte after each chunk record
  for (const auto& ch : full.chunks())
    chunk_ends.push_back(ch.offset + 9 + 8 + 8 + 8 + 4 + 4 + ch.compression.size() + 8 + ch.compressed_size);
  const auto bytes = file_bytes(file);
  const auto boundaries = record_boundaries(bytes);
  REQUIRE(boundaries.back() == bytes.size() - 8);  // the footer, then the closing magic
  const auto cut = tmp.path() / "cut.mcap";
  int cuts = 0;
  std::vector<std::size_t> lengths;
  for (std::size_t n = 8; n < bytes.size(); n += 97) lengths.push_back(n);
  for (std::size_t n = bytes.size() - 40; n < bytes.size(); ++n) lengths.push_back(n);  // footer and magic
  for (const std::size_t n : lengths) {
    INFO("cut at " << n << " of " << bytes.size());
    write_bytes(cut, bytes.data(), n);
    const McapReader r(cut);
    CHECK_FALSE(r.complete());
    std::size_t complete_chunks = 0;
    while (complete_chunks < chunk_ends.size() && chunk_ends[complete_chunks] <= n) ++complete_chunks;
    const std::vector<Written> want(written.begin(), written.begin() + std::ptrdiff_t(complete_chunks * 10));
    same_messages(r.messages(), want);
    CHECK(r.chunks().size() == complete_chunks);
    if (complete_chunks > 0) CHECK(r.channels().size() == 2);  // the chunk carries its channels
    const bool at_boundary = std::count(boundaries.begin(), boundaries.end(), n) > 0;
    CHECK(r.truncated() == !at_boundary);
    const auto last = *std::prev(std::upper_bound(boundaries.begin(), boundaries.end(), n));
    CHECK(r.dropped_bytes() == n - last);
    ++cuts;
  }
  CHECK(cuts > 10);
  // A file system that leaves zeros after the last write (a crash before the size was final): the zeros
  // are dropped like a record cut short.
  {
    std::vector<std::uint8_t> zeros(bytes.begin(), bytes.begin() + std::ptrdiff_t(full.chunks()[5].offset));
    zeros.resize(zeros.size() + 4096, 0);
    write_bytes(cut, zeros.data(), zeros.size());
    const McapReader r(cut);
    CHECK(r.truncated());
    CHECK(r.dropped_bytes() == 4096);
    CHECK(r.messages().size() == 50);
  }
  // The file cut exactly after a chunk's message indexes (what flush() leaves on disk): nothing dropped.
  const std::uint64_t after_third = full.chunks()[3].offset;  // = end of the third chunk's message indexes
  write_bytes(cut, bytes.data(), after_third);
  const McapReader clean(cut);
  CHECK_FALSE(clean.truncated());
  CHECK(clean.messages().size() == 30);
}

TEST_CASE("mcap file without messages is complete and keeps its channels", "[mcap]") {
  TempDir tmp;
  const auto file = tmp.path() / "empty.mcap";
  {
    McapWriter w;
    w.open(file);
    w.add_channel(w.add_schema("S", "jsonschema", "{}"), "/a", "json");
    w.flush();
  }
  const McapReader r(file);
  CHECK(r.complete());
  CHECK_FALSE(r.truncated());
  CHECK(r.messages().empty());
  CHECK(r.chunks().empty());
  REQUIRE(r.channels().size() == 1);
  CHECK(r.channels()[0].topic == "/a");
}

TEST_CASE("mcap recover rewrites a cut file as a complete one", "[mcap]") {
  TempDir tmp;
  const auto file = tmp.path() / "full.mcap";
  {
    McapOptions o;
    o.compression = McapCompression::Lz4;
    o.chunk_bytes = 1500;
    McapWriter w(o);
    w.open(file);
    const auto s = w.add_schema("S", "jsonschema", "{}");
    const auto ch = w.add_channel(s, "/a", "json", {{"x", "y"}});
    for (std::uint64_t i = 0; i < 400; ++i) {
      const auto d = payload(i);
      w.write(ch, 5000 - i, i, d.data(), d.size());  // descending times
    }
  }
  const auto bytes = file_bytes(file);
  const auto cut = tmp.path() / "cut.mcap";
  write_bytes(cut, bytes.data(), bytes.size() / 2);
  const McapReader before(cut);
  REQUIRE(before.truncated());
  REQUIRE(before.messages().size() > 50);
  const auto fixed = tmp.path() / "fixed.mcap";
  recover_mcap(cut, fixed);
  const McapReader after(fixed);
  CHECK(after.complete());
  CHECK_FALSE(after.truncated());
  REQUIRE(after.channels().size() == 1);
  CHECK(after.channels()[0].metadata.at("x") == "y");
  REQUIRE(after.messages().size() == before.messages().size());
  for (std::size_t i = 0; i < after.messages().size(); ++i) {
    CHECK(after.messages()[i].sequence == before.messages()[i].sequence);
    CHECK(after.messages()[i].log_time == before.messages()[i].log_time);
    CHECK(after.messages()[i].data == before.messages()[i].data);
  }
  for (std::size_t i = 1; i < after.messages().size(); ++i)
    CHECK(after.messages()[i - 1].log_time <= after.messages()[i].log_time);
}

TEST_CASE("mcap reader errors name the file and the offset", "[mcap]") {
  TempDir tmp;
  const auto text = tmp.path() / "notes.txt";
  { std::ofstream(text) << "time,x\n1,2\n"; }
  try {
    McapReader r(text);
    FAIL("no error");
  } catch (const McapError& e) {
    CHECK(std::string(e.what()).find("notes.txt") != std::string::npos);
    CHECK(std::string(e.what()).find("not an MCAP file") != std::string::npos);
    CHECK(e.offset() == 0);
  }
  CHECK_THROWS_AS(McapReader(tmp.path() / "missing.mcap"), std::runtime_error);
  { std::ofstream(tmp.path() / "empty.mcap"); }
  CHECK_THROWS_WITH(McapReader(tmp.path() / "empty.mcap"), Catch::Contains("empty file"));
  { std::ofstream(tmp.path() / "short.mcap") << "\x89MCA"; }
  CHECK_THROWS_WITH(McapReader(tmp.path() / "short.mcap"), Catch::Contains("too short"));

  // A chunk whose records were changed on disk: the CRC says so, at the chunk's offset.
  const auto file = tmp.path() / "raw.mcap";
  {
    McapOptions o;
    o.compression = McapCompression::None;
    McapWriter w(o);
    w.open(file);
    const auto ch = w.add_channel(0, "/a", "bytes");
    const std::vector<std::uint8_t> d(100, 0x55);
    w.write(ch, 1, 1, d.data(), d.size());
  }
  auto bytes = file_bytes(file);
  const McapReader good(file);
  REQUIRE(good.chunks().size() == 1);
  const std::vector<std::uint8_t> run(100, 0x55);
  const auto pos = std::search(bytes.begin(), bytes.end(), run.begin(), run.end());
  REQUIRE(pos != bytes.end());
  pos[50] = 0x56;
  const auto bad = tmp.path() / "bad.mcap";
  write_bytes(bad, bytes.data(), bytes.size());
  try {
    McapReader r(bad);
    FAIL("no error");
  } catch (const McapError& e) {
    CHECK(std::string(e.what()).find("CRC") != std::string::npos);
    CHECK(std::string(e.what()).find("bad.mcap") != std::string::npos);
    CHECK(e.offset() == good.chunks()[0].offset);
  }
}

TEST_CASE("mcap writer counts write errors instead of throwing", "[mcap]") {
  if (!fs::exists("/dev/full")) FAIL("/dev/full is needed by this test (Linux)");
  McapOptions o;
  o.compression = McapCompression::None;
  o.chunk_bytes = 4096;
  McapWriter w(o);
  w.open("/dev/full");
  const auto ch = w.add_channel(0, "/a", "bytes");
  const std::vector<std::uint8_t> d(1000, 1);
  for (int i = 0; i < 500; ++i) CHECK_NOTHROW(w.write(ch, std::uint64_t(i), 0, d.data(), d.size()));
  CHECK_NOTHROW(w.close());
  CHECK(w.write_errors() > 0);
  CHECK(w.messages() == 500);
}

TEST_CASE("mcap writer rejects unknown ids and unwritable paths", "[mcap]") {
  TempDir tmp;
  McapWriter w;
  try {
    w.open(tmp.path() / "no" / "such" / "dir" / "x.mcap");
    FAIL("no error");
  } catch (const std::runtime_error& e) {
    CHECK(std::string(e.what()).find("x.mcap") != std::string::npos);
  }
  w.open(tmp.path() / "x.mcap");
  CHECK_THROWS_AS(w.add_channel(3, "/a", "cdr"), std::invalid_argument);
  const std::uint8_t b = 0;
  CHECK_THROWS_AS(w.write(1, 0, 0, &b, 1), std::invalid_argument);
}

TEST_CASE("mcap writer allocates nothing per message once its buffers have grown", "[mcap]") {
  const auto c = GENERATE(McapCompression::None, McapCompression::Zstd, McapCompression::Lz4);
  INFO(to_string(c));
  TempDir tmp;
  McapOptions o;
  o.compression = c;
  o.chunk_bytes = 64 * 1024;
  McapWriter w(o);
  w.open(tmp.path() / "a.mcap");
  std::vector<std::uint16_t> channels;
  for (int i = 0; i < 3; ++i) channels.push_back(w.add_channel(0, "/c" + std::to_string(i), "bytes"));
  std::vector<std::uint8_t> d(44, 7);
  auto burst = [&](std::uint64_t from, std::uint64_t count) {
    for (std::uint64_t i = from; i < from + count; ++i) w.write(channels[i % 3], i, i, d.data(), d.size());
  };
  burst(0, 20000);  // warm-up: about 20 chunks, the buffers reach their working size
  g_allocations = 0;
  g_count_allocations = true;
  burst(20000, 20000);
  g_count_allocations = false;
  const std::uint64_t allocations = g_allocations;
  // Per chunk: its index entry (a few allocations, about 20 chunks); none per message.
  CHECK(allocations < 200);
  w.close();
  CHECK(w.write_errors() == 0);
  CHECK(McapReader(tmp.path() / "a.mcap").messages().size() == 40000);
}

namespace {
std::uint64_t le(const std::vector<std::uint8_t>& b, std::size_t at, int n) {
  std::uint64_t v = 0;
  for (int i = n - 1; i >= 0; --i) v = v << 8 | b[at + std::size_t(i)];
  return v;
}
}  // namespace

TEST_CASE("mcap message indexes point at their messages", "[mcap]") {
  TempDir tmp;
  const auto file = tmp.path() / "raw.mcap";
  McapOptions o;
  o.compression = McapCompression::None;  // the chunk's records readable in place
  o.chunk_bytes = 3000;
  {
    McapWriter w(o);
    w.open(file);
    const auto a = w.add_channel(0, "/a", "bytes");
    const auto b = w.add_channel(0, "/b", "bytes");
    for (std::uint64_t i = 0; i < 700; ++i) {
      const auto d = payload(i);
      w.write(i % 4 == 0 ? b : a, 9000 - i, 0, d.data(), d.size());
    }
  }
  const auto bytes = file_bytes(file);
  std::size_t at = 8, chunks = 0, indexed = 0, messages = 0;
  std::size_t records = 0, records_end = 0;              // the last chunk's records, in the file
  while (at + 9 <= bytes.size() && bytes[at] != 0x0F) {  // up to DataEnd
    const std::uint8_t op = bytes[at];
    const std::size_t len = le(bytes, at + 1, 8), body = at + 9;
    if (op == 0x06) {
      ++chunks;
      const std::size_t compression_len = le(bytes, body + 28, 4);
      records = body + 32 + compression_len + 8;
      records_end = records + le(bytes, body + 32 + compression_len, 8);
      for (std::size_t r = records; r < records_end; r += 9 + le(bytes, r + 1, 8))
        messages += bytes[r] == 0x05;
    } else if (op == 0x07) {
      const auto channel = le(bytes, body, 2);
      const std::size_t n = le(bytes, body + 2, 4) / 16;
      for (std::size_t k = 0; k < n; ++k) {
        const auto time = le(bytes, body + 6 + 16 * k, 8), offset = le(bytes, body + 14 + 16 * k, 8);
        REQUIRE(records + offset < records_end);
        CHECK(bytes[records + offset] == 0x05);
        CHECK(le(bytes, records + offset + 9, 2) == channel);
        CHECK(le(bytes, records + offset + 15, 8) == time);
        ++indexed;
      }
    }
    at = body + len;
  }
  CHECK(chunks > 10);
  CHECK(messages == 700);
  CHECK(indexed == 700);
}

TEST_CASE("mcap writer keeps its channels across files", "[mcap]") {
  TempDir tmp;
  McapWriter w;
  const auto ch = w.add_channel(w.add_schema("S", "jsonschema", "{}"), "/a", "json");  // before open()
  const std::uint8_t d[2] = {'{', '}'};
  for (const char* name : {"one.mcap", "two.mcap"}) {
    w.open(tmp.path() / name);
    for (std::uint64_t i = 0; i < 3; ++i) w.write(ch, i, i, d, 2);
  }
  w.close();
  for (const char* name : {"one.mcap", "two.mcap"}) {
    INFO(name);
    const McapReader r(tmp.path() / name);
    CHECK(r.complete());
    REQUIRE(r.schemas().size() == 1);
    REQUIRE(r.channels().size() == 1);
    REQUIRE(r.messages().size() == 3);
    CHECK(r.messages()[0].sequence == 0);
    CHECK(r.messages()[2].sequence == 2);
  }
}
