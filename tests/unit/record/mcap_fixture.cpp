// shapeform_mcap_fixture DIR: writes the MCAP files tests/npm/mcap_check_test.py gives to the readers
// others wrote (tests/npm/mcap_check.mjs), and what shapeform's own reader reads back from them.
//   DIR/complete_{none,zstd,lz4}.mcap   complete files: a cdr channel (a hand-encoded XCDR1 struct with
//                                      its omgidl schema) and a json channel (jsonschema)
//   DIR/killed.mcap                    the zstd file cut inside its last chunks (a hard kill)
//   DIR/X.expected.jsonl               per file: {topic, log_time, message} per message, as McapReader
//                                      reads it back, the cdr payload decoded here by hand
// Exit 0, or 1 with the reason.
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "record/mcap.hpp"

using namespace shapeform::record;
namespace fs = std::filesystem;

namespace {

const char* kIdl = R"(module shapeform {
  module test {
    /// A sample with every alignment case: u32, then a double (padded to 8), an int32, a string.
    struct Sample {
      uint32 id;
      double x;
      int32 step;
      string label;
    };
  };
};
)";

const char* kJsonSchema =
    R"({"type": "object", "properties": {"id": {"type": "integer"}, "note": {"type": "string"}}})";

/// XCDR1 little-endian, 4-byte encapsulation header 00 01 00 00; alignment counted after the header.
std::vector<std::uint8_t> encode(std::uint32_t id, double x, std::int32_t step, const std::string& label) {
  std::vector<std::uint8_t> b = {0x00, 0x01, 0x00, 0x00};
  auto align = [&](std::size_t n) {
    while ((b.size() - 4) % n != 0) b.push_back(0);
  };
  auto raw = [&](const void* p, std::size_t n) {
    const auto* c = static_cast<const std::uint8_t*>(p);
    b.insert(b.end(), c, c + n);  // the host is little-endian (x86-64, checked in main)
  };
  align(4);
  raw(&id, 4);
  align(8);
  raw(&x, 8);
  align(4);
  raw(&step, 4);
  align(4);
  const std::uint32_t n = std::uint32_t(label.size() + 1);
  raw(&n, 4);
  raw(label.c_str(), label.size() + 1);
  return b;
}

nlohmann::json decode(const std::vector<std::uint8_t>& b) {
  if (b.size() < 4 + 28 || b[1] != 0x01) throw std::runtime_error("bad CDR payload");
  std::uint32_t id, n;
  double x;
  std::int32_t step;
  std::memcpy(&id, b.data() + 4, 4);
  std::memcpy(&x, b.data() + 12, 8);
  std::memcpy(&step, b.data() + 20, 4);
  std::memcpy(&n, b.data() + 24, 4);
  return {{"id", id},
          {"x", x},
          {"step", step},
          {"label", std::string(reinterpret_cast<const char*>(b.data() + 28), n - 1)}};
}

void write_file(const fs::path& path, McapCompression compression) {
  McapOptions o;
  o.compression = compression;
  o.chunk_bytes = 4096;  // many chunks
  McapWriter w(o);
  w.open(path);
  const auto sample = w.add_schema("shapeform::test::Sample", "omgidl", kIdl);
  const auto note = w.add_schema("shapeform.Note", "jsonschema", kJsonSchema);
  const auto samples = w.add_channel(sample, "/shapeform/samples", "cdr", {{"qos", "reliable"}});
  const auto notes = w.add_channel(note, "/shapeform/notes", "json");
  for (std::uint32_t i = 0; i < 600; ++i) {
    const std::uint64_t t = 1'700'000'000'000'000'000ull + std::uint64_t(i) * 50'000'000ull;
    const auto b = encode(i, 0.1 * i - 7.25, std::int32_t(i) * -3, "agent " + std::to_string(i % 17));
    w.write(samples, t, t, b.data(), b.size());
    if (i % 25 == 0) {
      const std::string j =
          nlohmann::json{{"id", i}, {"note", "checkpoint \"" + std::to_string(i) + "\""}}.dump();
      w.write(notes, t, t, reinterpret_cast<const std::uint8_t*>(j.data()), j.size());
    }
  }
  w.close();
  if (w.write_errors() != 0) throw std::runtime_error("write errors in " + path.string());
}

void expect(const fs::path& path) {
  McapReader r(path);
  std::map<std::uint16_t, McapChannel> channels;
  for (const auto& c : r.channels()) channels[c.id] = c;
  std::ofstream out(fs::path(path).replace_extension(".expected.jsonl"));
  for (const auto& m : r.messages()) {
    const auto& c = channels.at(m.channel);
    nlohmann::json message = c.message_encoding == "cdr"
                                 ? decode(m.data)
                                 : nlohmann::json::parse(std::string(m.data.begin(), m.data.end()));
    out << nlohmann::json{{"topic", c.topic}, {"log_time", std::to_string(m.log_time)}, {"message", message}}
               .dump()
        << '\n';
  }
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 2) {
    std::cerr << "usage: shapeform_mcap_fixture DIR\n";
    return 2;
  }
  const std::uint16_t one = 1;
  if (*reinterpret_cast<const std::uint8_t*>(&one) != 1) {
    std::cerr << "shapeform_mcap_fixture: encodes little-endian CDR on a little-endian host only\n";
    return 1;
  }
  try {
    const fs::path dir = argv[1];
    fs::create_directories(dir);
    for (const auto c : {McapCompression::None, McapCompression::Zstd, McapCompression::Lz4}) {
      const auto p = dir / (std::string("complete_") + to_string(c) + ".mcap");
      write_file(p, c);
      expect(p);
    }
    // A hard kill: the zstd file cut 70 % of the way into its data section (inside a chunk's records or
    // its message indexes), summary and footer gone.
    const auto full = dir / "complete_zstd.mcap";
    const auto killed = dir / "killed.mcap";
    fs::copy_file(full, killed, fs::copy_options::overwrite_existing);
    fs::resize_file(killed, fs::file_size(full) * 7 / 10);
    expect(killed);
    McapReader k(killed);
    if (k.complete() || k.messages().empty())
      throw std::runtime_error("killed.mcap: expected a partial file");
  } catch (const std::exception& e) {
    std::cerr << "shapeform_mcap_fixture: " << e.what() << '\n';
    return 1;
  }
  return 0;
}
