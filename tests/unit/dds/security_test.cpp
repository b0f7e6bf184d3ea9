// Unit tests of DDS Security's edges (common/protocol/security, the participant factory, library_log): the
// enclave check names the bad file for each way a keystore goes wrong, the factory never creates an
// unsecured participant instead, the keys validate, and secured nodes exchange samples only within
// their permissions. Keystores come from scripts/make_keystore.sh (openssl), made in a temporary folder.
#include <unistd.h>

#include <catch2/catch.hpp>
#include <array>
#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <memory>
#include <set>
#include <fstream>
#include <string>
#include <thread>
#include <vector>

#include "config/config.hpp"
#include "dds/handshake_filter.hpp"
#include "dds/library_log.hpp"
#include "dds/node.hpp"
#include "dds/participant_factory.hpp"
#include "force_transport.hpp"
#include "protocol/security.hpp"
#include "protocol/transport.hpp"

namespace shapeform {
namespace {

namespace fs = std::filesystem;

/// A temporary folder, removed with its contents at scope exit.
struct TempDir {
  fs::path path;
  TempDir() {
    std::string tmpl = (fs::temp_directory_path() / "shapeform_security_XXXXXX").string();
    REQUIRE(::mkdtemp(tmpl.data()) != nullptr);
    path = tmpl;
  }
  ~TempDir() {
    std::error_code ec;
    fs::remove_all(path, ec);
  }
};

/// Runs a shell command; REQUIREs exit 0.
void run(const std::string& command) {
  INFO(command);
  REQUIRE(std::system((command + " >/dev/null 2>&1").c_str()) == 0);
}

std::string make_keystore(const fs::path& dir, const std::string& args) {
  run(std::string(SHAPEFORM_SOURCE_DIR) + "/scripts/make_keystore.sh " + dir.string() + " " + args);
  return dir.string();
}

dds::SecurityConfig secured(const std::string& keystore, const std::string& identity) {
  dds::SecurityConfig s;
  s.enabled = true;
  s.keystore = keystore;
  s.identity = identity;
  return s;
}

/// The SecurityError check_enclave throws, or "" when it passes.
std::string problem(const dds::SecurityConfig& s) {
  try {
    dds::check_enclave(s);
  } catch (const dds::SecurityError& e) {
    return e.what();
  }
  return "";
}

void copy_over(const fs::path& from, const fs::path& to) {
  fs::copy_file(from, to, fs::copy_options::overwrite_existing);
}

}  // namespace

TEST_CASE("a keystore's enclaves pass the check; each broken file is named", "[dds][security]") {
  TempDir tmp;
  const std::string ks = make_keystore(tmp.path / "ks", "--agents 2");
  const fs::path enclaves = tmp.path / "ks" / "enclaves";
  for (const char* name : {"supervisor", "viewer", "agent_0", "agent_1"}) {
    INFO(name);
    CHECK(problem(secured(ks, name)).empty());
  }

  SECTION("no keystore, no enclave") {
    CHECK_THAT(problem(secured((tmp.path / "nowhere").string(), "agent_0")),
               Catch::Contains("security.keystore: no keystore folder") && Catch::Contains("make_keystore.sh"));
    CHECK_THAT(problem(secured(ks, "agent_7")),
               Catch::Contains("no enclave agent_7") && Catch::Contains("--enclave agent_7"));
    CHECK_THAT(problem(secured(ks, "../agent_0")), Catch::Contains("cannot name an enclave"));
  }
  SECTION("a missing file") {
    fs::remove(enclaves / "agent_1" / "permissions.p7s");
    CHECK_THAT(problem(secured(ks, "agent_1")),
               Catch::Contains((enclaves / "agent_1" / "permissions.p7s").string() + " does not exist"));
  }
  SECTION("a key of another identity") {
    copy_over(enclaves / "agent_0" / "key.pem", enclaves / "agent_1" / "key.pem");
    CHECK_THAT(problem(secured(ks, "agent_1")),
               Catch::Contains((enclaves / "agent_1" / "key.pem").string() + " does not belong to"));
  }
  SECTION("not a certificate") {
    std::ofstream(enclaves / "agent_1" / "cert.pem") << "hello\n";
    CHECK_THAT(problem(secured(ks, "agent_1")), Catch::Contains("cert.pem is not a PEM certificate"));
  }
  SECTION("a certificate and key of another authority") {
    make_keystore(tmp.path / "other", "--agents 2");
    for (const char* f : {"cert.pem", "key.pem"})
      copy_over(tmp.path / "other" / "enclaves" / "agent_1" / f, enclaves / "agent_1" / f);
    CHECK_THAT(problem(secured(ks, "agent_1")),
               Catch::Contains("cert.pem was not issued by " + (enclaves / "agent_1" / "identity_ca.cert.pem").string()));
  }
  SECTION("permissions changed after signing, or signed by someone else") {
    const fs::path p7s = enclaves / "agent_1" / "permissions.p7s";
    std::ifstream in(p7s);
    std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    const auto at = text.find("shapeform/state");
    REQUIRE(at != std::string::npos);
    text.replace(at, 15, "shapeform/comma");  // same length: only the signature can tell
    std::ofstream(p7s) << text;
    CHECK_THAT(problem(secured(ks, "agent_1")),
               Catch::Contains("permissions.p7s: its signature does not verify against"));

    // Signed by the agent's own key (which chains to the identity authority, not the permissions one).
    const fs::path e = enclaves / "agent_0";
    run("openssl smime -sign -in " + (e / "permissions.xml").string() + " -text -out " + (e / "permissions.p7s").string() +
        " -signer " + (e / "cert.pem").string() + " -inkey " + (e / "key.pem").string());
    CHECK_THAT(problem(secured(ks, "agent_0")), Catch::Contains("permissions.p7s: its signature does not verify"));
  }
  SECTION("an expired certificate") {
    // Made 10 days ago, valid for 5: expired 5 days ago (faketime moves only this script's clock).
    run("faketime -f -10d " + std::string(SHAPEFORM_SOURCE_DIR) + "/scripts/make_keystore.sh " +
        (tmp.path / "old").string() + " --enclave agent_0 --days 5");
    CHECK_THAT(problem(secured((tmp.path / "old").string(), "agent_0")),
               Catch::Contains((tmp.path / "old" / "enclaves" / "agent_0" / "cert.pem").string() + " expired on"));
  }
}

TEST_CASE("security properties name the enclave's six files and the three builtin plugins", "[dds][security]") {
  const auto props = dds::security_properties(secured("/ks", "agent_3"));
  const auto value = [&](const std::string& key) {
    for (const auto& [k, v] : props)
      if (k == key) return v;
    return std::string("(missing)");
  };
  CHECK(value("dds.sec.auth.plugin") == "builtin.PKI-DH");
  CHECK(value("dds.sec.access.plugin") == "builtin.Access-Permissions");
  CHECK(value("dds.sec.crypto.plugin") == "builtin.AES-GCM-GMAC");
  CHECK(value("dds.sec.auth.builtin.PKI-DH.identity_ca") == "file:///ks/enclaves/agent_3/identity_ca.cert.pem");
  CHECK(value("dds.sec.auth.builtin.PKI-DH.identity_certificate") == "file:///ks/enclaves/agent_3/cert.pem");
  CHECK(value("dds.sec.auth.builtin.PKI-DH.private_key") == "file:///ks/enclaves/agent_3/key.pem");
  CHECK(value("dds.sec.access.builtin.Access-Permissions.permissions_ca") ==
        "file:///ks/enclaves/agent_3/permissions_ca.cert.pem");
  CHECK(value("dds.sec.access.builtin.Access-Permissions.governance") == "file:///ks/enclaves/agent_3/governance.p7s");
  CHECK(value("dds.sec.access.builtin.Access-Permissions.permissions") ==
        "file:///ks/enclaves/agent_3/permissions.p7s");
  CHECK(props.size() == 9);

  // The participant QoS carries them only when enabled.
  dds::TransportConfig cfg;
  const auto count = [](const eprosima::fastdds::dds::DomainParticipantQos& q) {
    int n = 0;
    for (const auto& p : q.properties().properties()) n += p.name().rfind("dds.sec.", 0) == 0;
    return n;
  };
  CHECK(count(dds::participant_qos(cfg, "x")) == 0);
  cfg.security = secured("/ks", "agent_3");
  CHECK(count(dds::participant_qos(cfg, "x")) == 9);
}

TEST_CASE("security keys: validated, identity derived from the role", "[dds][security][config]") {
  CHECK_THROWS_WITH(config::load("", {"security.enabled=true"}),
                    Catch::Contains("security.keystore: must name a keystore folder"));
  CHECK_THROWS_WITH(config::load("", {"security.enabled=true", "security.keystore=/k", "transport.profile=discovery-server"}),
                    Catch::Contains("security.enabled: cannot be used with transport.profile discovery-server"));
  // Multicast discovery (lan without peers) races in Fast DDS 2.9.1's handshake matching: refused; lan
  // with peers and loopback (unicast discovery, one receive thread for announcements) are fine.
  CHECK_THROWS_WITH(config::load("", {"security.enabled=true", "security.keystore=/k", "transport.profile=lan"}),
                    Catch::Contains("security.enabled: cannot be used with multicast discovery (transport.profile "
                                    "lan without transport.peers)") &&
                        Catch::Contains("list every host's address in transport.peers"));
  CHECK_NOTHROW(config::load("", {"security.enabled=true", "security.keystore=/k", "transport.profile=lan",
                                  "transport.peers=[10.1.2.3]"}));
  // Each address of transport.interfaces is a receive thread: one (or none: all, one socket) only.
  CHECK_THROWS_WITH(config::load("", {"security.enabled=true", "security.keystore=/k", "transport.profile=lan",
                                      "transport.peers=[10.1.2.3]", "transport.interfaces=[10.1.2.3,10.1.3.3]"}),
                    Catch::Contains("security.enabled: cannot be used with more than one address in "
                                    "transport.interfaces"));
  CHECK_NOTHROW(config::load("", {"security.enabled=true", "security.keystore=/k", "transport.profile=lan",
                                  "transport.peers=[10.1.2.3]", "transport.interfaces=[10.1.2.3]"}));
  CHECK_NOTHROW(config::load("", {"transport.profile=lan", "transport.peers=[10.1.2.3]",
                                  "transport.interfaces=[10.1.2.3,10.1.3.3]"}));
  CHECK_NOTHROW(config::load("", {"transport.profile=lan"}));
  CHECK_THROWS_WITH(config::load("", {"security.identity=../etc"}),
                    Catch::Contains("security.identity: must be empty or an enclave name"));
  const auto c = config::load("", {"security.enabled=true", "security.keystore=/k"});
  CHECK(c.transport.security.enabled);
  CHECK(dds::with_identity(c.transport, "supervisor").security.identity == "supervisor");
  const auto named = config::load("", {"security.identity=viewer"});
  CHECK(dds::with_identity(named.transport, "supervisor").security.identity == "viewer");
  CHECK(dds::describe(dds::with_identity(c.transport, "agent_2")).find("secured as agent_2 (keystore /k)") !=
        std::string::npos);
}

TEST_CASE("Fast DDS's permission refusals are read from its log lines", "[dds][security]") {
  const auto r = dds::permission_refusal(
      "Error validating remote permissions for a6.95.89.78.4f.da.0d.b8.24.bb.4a.4d|0.0.1.c1 (Remote participant "
      "PermissionsCA differs from local)");
  REQUIRE(r);
  CHECK(dds::to_string(*r) == "a6.95.89.78.4f.da.0d.b8.24.bb.4a.4d");
  const auto c = dds::permission_refusal("Error checking remote participant  01.0f.00.00.00.00.00.00.00.00.00.09 (x)");
  REQUIRE(c);
  CHECK(dds::to_string(*c) == "01.0f.00.00.00.00.00.00.00.00.00.09");
  CHECK_FALSE(dds::permission_refusal("Remote participant PermissionsCA differs from local"));
  CHECK_FALSE(dds::permission_refusal("Error validating remote permissions for zz.95"));
}

TEST_CASE("secured nodes: a bad enclave is refused, never run unsecured; permissions bound endpoints",
          "[dds][security][node]") {
  TempDir tmp;
  const std::string ks = make_keystore(tmp.path / "ks", "--agents 1");
  dds::TransportConfig cfg;
  cfg.domain = 150 + 5 * static_cast<int>(::getpid() % 16) + 1;
  cfg.security = secured(ks, "agent_0");

  // No participant from a broken enclave: SecurityError naming the file.
  fs::remove(tmp.path / "ks" / "enclaves" / "viewer" / "key.pem");
  dds::TransportConfig broken = cfg;
  broken.security.identity = "viewer";
  CHECK_THROWS_WITH(dds::create_participant(broken, "x"), Catch::Contains("viewer/key.pem does not exist"));
  CHECK_THROWS_AS(dds::create_participant(broken, "x"), dds::SecurityError);

  // An agent's permissions: it publishes state, never a command.
  dds::Node agent(cfg, "agent");
  auto state = agent.writer<msg::AgentState>(dds::TopicId::State);
  CHECK(state.valid());
  CHECK_THROWS_WITH(agent.writer<msg::ShapeCommand>(dds::TopicId::Command),
                    Catch::Contains("do not allow publishing shapeform/command"));

  // The supervisor hears the agent's state through the encrypted topic.
  dds::TransportConfig sup_cfg = cfg;
  sup_cfg.security.identity = "supervisor";
  dds::Node supervisor(sup_cfg, "supervisor");
  auto reader = supervisor.reader<msg::AgentState>(dds::TopicId::State);
  std::vector<dds::Received<msg::AgentState>> got;
  msg::AgentState m;
  m.id(0);
  m.x(1.25);
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(20);
  while (got.empty() && std::chrono::steady_clock::now() < deadline) {
    state.write(m);
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
    reader.drain(got);
  }
  REQUIRE_FALSE(got.empty());
  CHECK(got.front().msg.x() == 1.25);
}

namespace {

/// An RTPS datagram as Fast DDS 2.9.1's participant stateless writer sends a handshake: the header, an
/// INFO_DST naming the participant the datagram goes to, an INFO_TS, then a DATA of `writer` whose
/// payload is a ParticipantGenericMessage for `destination` (the fields after it left out: the filter
/// reads no further). Submessages in the given byte order; `inline_qos` adds a parameter list.
std::vector<std::uint8_t> handshake_datagram(std::uint8_t info_dst, std::uint8_t destination,
                                             std::array<std::uint8_t, 4> writer = {0x00, 0x02, 0x01, 0xc3},
                                             bool little_endian = true, bool inline_qos = false) {
  std::vector<std::uint8_t> d = {'R', 'T', 'P', 'S', 2, 3, 1, 15};
  for (int i = 0; i < 12; ++i) d.push_back(0xa0);  // the sender's prefix
  const auto u16 = [&](std::vector<std::uint8_t>& v, std::uint16_t x) {
    if (little_endian) {
      v.push_back(static_cast<std::uint8_t>(x & 0xff));
      v.push_back(static_cast<std::uint8_t>(x >> 8));
    } else {
      v.push_back(static_cast<std::uint8_t>(x >> 8));
      v.push_back(static_cast<std::uint8_t>(x & 0xff));
    }
  };
  const std::uint8_t e = little_endian ? 1 : 0;
  d.insert(d.end(), {0x0e, e});
  u16(d, 12);
  for (int i = 0; i < 12; ++i) d.push_back(info_dst);
  d.insert(d.end(), {0x09, e});
  u16(d, 8);
  for (int i = 0; i < 8; ++i) d.push_back(0x11);
  std::vector<std::uint8_t> body;
  u16(body, 0);   // extraFlags
  u16(body, 16);  // octetsToInlineQos
  body.insert(body.end(), {0x00, 0x02, 0x01, 0xc4});  // reader: the stateless reader
  body.insert(body.end(), writer.begin(), writer.end());
  for (int i = 0; i < 8; ++i) body.push_back(0);  // writer sequence number
  if (inline_qos) {
    u16(body, 0x0070);  // PID_KEY_HASH
    u16(body, 16);
    for (int i = 0; i < 16; ++i) body.push_back(0x33);
    u16(body, 0x0001);  // PID_SENTINEL
    u16(body, 0);
  }
  body.insert(body.end(), {0x00, 0x01, 0x00, 0x00});  // encapsulation CDR_LE
  for (int i = 0; i < 48; ++i) body.push_back(0x22);  // message_identity, related_message_identity
  for (int i = 0; i < 12; ++i) body.push_back(destination);
  for (int i = 0; i < 4; ++i) body.push_back(0x00);
  for (int i = 0; i < 100; ++i) body.push_back(0x44);  // the rest of the message
  const std::uint8_t flags = static_cast<std::uint8_t>(e | 0x04 | (inline_qos ? 0x02 : 0x00));
  d.insert(d.end(), {0x15, flags});
  u16(d, static_cast<std::uint16_t>(body.size()));
  d.insert(d.end(), body.begin(), body.end());
  return d;
}

bool misdirected(const std::vector<std::uint8_t>& d) { return dds::is_misdirected_handshake(d.data(), d.size()); }

}  // namespace

TEST_CASE("a handshake datagram for another participant than it goes to is misdirected; nothing else is",
          "[dds][security][handshake_filter]") {
  // Going to participant 0x07 with a handshake for 0x09: every other participant's datagram of it.
  CHECK(misdirected(handshake_datagram(0x07, 0x09)));
  CHECK(misdirected(handshake_datagram(0x07, 0x09, {0x00, 0x02, 0x01, 0xc3}, false)));
  CHECK(misdirected(handshake_datagram(0x07, 0x09, {0x00, 0x02, 0x01, 0xc3}, true, true)));
  // The one for the participant it goes to.
  CHECK_FALSE(misdirected(handshake_datagram(0x09, 0x09)));
  CHECK_FALSE(misdirected(handshake_datagram(0x09, 0x09, {0x00, 0x02, 0x01, 0xc3}, false, true)));
  // No destination named, or no INFO_DST: for everyone.
  CHECK_FALSE(misdirected(handshake_datagram(0x07, 0x00)));
  CHECK_FALSE(misdirected(handshake_datagram(0x00, 0x09)));
  // Another writer (the secure volatile writer 0xff0202c3, a user writer): never touched.
  CHECK_FALSE(misdirected(handshake_datagram(0x07, 0x09, {0xff, 0x02, 0x02, 0xc3})));
  CHECK_FALSE(misdirected(handshake_datagram(0x07, 0x09, {0x00, 0x00, 0x01, 0x03})));

  auto d = handshake_datagram(0x07, 0x09);
  SECTION("two misdirected handshakes in one datagram") {
    auto second = handshake_datagram(0x07, 0x0a);
    d.insert(d.end(), second.begin() + 20 + 16 + 12, second.end());  // its DATA only
    CHECK(misdirected(d));
  }
  SECTION("a handshake for the destination beside a misdirected one keeps the datagram") {
    auto second = handshake_datagram(0x07, 0x07);
    d.insert(d.end(), second.begin() + 20 + 16 + 12, second.end());
    CHECK_FALSE(misdirected(d));
  }
  SECTION("a vendor-specific submessage after it (Debian's Fast DDS appends one of 56 bytes)") {
    d.insert(d.end(), {0x80, 0x01, 56, 0});
    d.insert(d.end(), 56, 0x55);
    CHECK(misdirected(d));
  }
  SECTION("any other submessage keeps it (HEARTBEAT, a protected SEC_PREFIX)") {
    for (std::uint8_t id : {std::uint8_t{0x07}, std::uint8_t{0x31}}) {
      auto with = d;
      with.insert(with.end(), {id, 0x01, 4, 0, 0, 0, 0, 0});
      CHECK_FALSE(misdirected(with));
    }
  }
  SECTION("truncated anywhere, or not RTPS: kept") {
    for (std::size_t n = 0; n < d.size() - 100; ++n) {
      INFO("cut to " << n << " bytes");
      CHECK_FALSE(dds::is_misdirected_handshake(d.data(), n));
    }
    d[0] = 'X';
    CHECK_FALSE(misdirected(d));
    CHECK_FALSE(dds::is_misdirected_handshake(nullptr, 0));
  }
  SECTION("a DATA without payload (no D flag) or a DATA_FRAG: kept") {
    auto no_data = d;
    no_data[20 + 16 + 12 + 1] &= static_cast<std::uint8_t>(~0x04);
    CHECK_FALSE(misdirected(no_data));
    auto frag = d;
    frag[20 + 16 + 12] = 0x16;
    CHECK_FALSE(misdirected(frag));
  }
}

TEST_CASE("secured participants send each handshake only to the participant it names, and authenticate",
          "[dds][security][handshake_filter][node]") {
  TempDir tmp;
  const std::string ks = make_keystore(tmp.path / "ks", "--agents 3");
  dds::TransportConfig cfg;
  cfg.domain = 150 + 5 * static_cast<int>(::getpid() % 16) + 2;
  test::force_transport();  // one process: the handshakes through the transport, not intraprocess
  const auto before = dds::handshake_filter_counts();

  // Four participants in one process (three agents and the supervisor): each handshake message would
  // go to the three others without the filter.
  std::vector<std::unique_ptr<dds::Node>> agents;
  std::vector<dds::Writer<msg::AgentState>> writers;
  for (int i = 0; i < 3; ++i) {
    dds::TransportConfig c = cfg;
    c.security = secured(ks, "agent_" + std::to_string(i));
    agents.push_back(std::make_unique<dds::Node>(c, "agent_" + std::to_string(i)));
    writers.push_back(agents.back()->writer<msg::AgentState>(dds::TopicId::State));
  }
  dds::TransportConfig sup_cfg = cfg;
  sup_cfg.security = secured(ks, "supervisor");
  dds::Node supervisor(sup_cfg, "supervisor");
  auto reader = supervisor.reader<msg::AgentState>(dds::TopicId::State);

  // The supervisor hears all three through the encrypted topic: every pair authenticated.
  std::set<std::uint32_t> heard;
  std::vector<dds::Received<msg::AgentState>> got;
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(30);
  while (heard.size() < 3 && std::chrono::steady_clock::now() < deadline) {
    for (std::uint32_t i = 0; i < 3; ++i) {
      msg::AgentState m;
      m.id(i);
      writers[i].write(m);
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
    got.clear();
    reader.drain(got);
    for (const auto& r : got) heard.insert(r.msg.id());
  }
  CHECK(heard.size() == 3);
  const auto after = dds::handshake_filter_counts();
  // Misdirected copies were held back (each message would also have gone to the participants already
  // discovered that it does not name), and none arrived.
  CHECK(after.dropped > before.dropped);
  CHECK(after.misdirected_received == before.misdirected_received);
}

}  // namespace shapeform
