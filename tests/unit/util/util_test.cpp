#include <unistd.h>

#include <algorithm>
#include <catch2/catch.hpp>
#include <chrono>
#include <cmath>
#include <csignal>
#include <map>
#include <memory>
#include <numeric>
#include <random>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "util/id_map.hpp"
#include "util/log.hpp"
#include "util/phase_clock.hpp"
#include "util/proc_stats.hpp"
#include "util/signals.hpp"
#include "util/stats.hpp"
#include "util/text.hpp"

using namespace std::chrono_literals;
namespace util = shapeform::util;

TEST_CASE("percentile: nearest rank on small examples", "[util][stats]") {
  std::vector<double> empty;
  CHECK_FALSE(util::percentile(empty, 50.0).has_value());

  std::vector<double> one{7.0};
  CHECK(*util::percentile(one, 0.0) == 7.0);
  CHECK(*util::percentile(one, 99.0) == 7.0);

  std::vector<double> v{5, 1, 4, 2, 3};
  CHECK(*util::percentile(v, 0.0) == 1.0);
  CHECK(*util::percentile(v, 20.0) == 1.0);
  CHECK(*util::percentile(v, 21.0) == 2.0);
  CHECK(*util::percentile(v, 50.0) == 3.0);
  CHECK(*util::percentile(v, 100.0) == 5.0);
  CHECK(*util::percentile(v, 250.0) == 5.0);  // clamped
  CHECK(*util::percentile(v, -3.0) == 1.0);   // clamped
  CHECK_FALSE(util::percentile(v, std::nan("")).has_value());

  std::vector<double> hundred(100);
  std::iota(hundred.begin(), hundred.end(), 1.0);  // 1..100
  std::shuffle(hundred.begin(), hundred.end(), std::mt19937(7));
  CHECK(*util::percentile(hundred, 99.0) == 99.0);  // not rounded up to the max
  CHECK(*util::percentile(hundred, 90.0) == 90.0);
}

TEST_CASE("percentile: property checks against a sorted copy", "[util][stats]") {
  std::mt19937 rng(42);
  std::uniform_int_distribution<int> size_dist(1, 300);
  std::normal_distribution<double> value_dist(0.0, 10.0);
  std::uniform_real_distribution<double> p_dist(0.0, 100.0);
  for (int trial = 0; trial < 200; ++trial) {
    std::vector<double> v(static_cast<std::size_t>(size_dist(rng)));
    for (auto& x : v) x = value_dist(rng);
    std::vector<double> sorted = v;
    std::sort(sorted.begin(), sorted.end());
    const double p = p_dist(rng);
    const double q = *util::percentile(v, p);
    // A sample of v; at least p % of samples are <= q, and fewer than p % are < q.
    const auto le = std::upper_bound(sorted.begin(), sorted.end(), q) - sorted.begin();
    const auto lt = std::lower_bound(sorted.begin(), sorted.end(), q) - sorted.begin();
    const double n = static_cast<double>(sorted.size());
    REQUIRE(std::binary_search(sorted.begin(), sorted.end(), q));
    REQUIRE(static_cast<double>(le) >= p / 100.0 * n - 1e-9);
    REQUIRE(static_cast<double>(lt) < std::max(1.0, p / 100.0 * n));
  }
}

namespace {

struct FakeNow {
  std::chrono::steady_clock::time_point t{std::chrono::seconds(50)};
};

}  // namespace

TEST_CASE("ThrottledLog allows a key once per interval and counts the rest", "[util][log]") {
  auto fake = std::make_shared<FakeNow>();
  util::ThrottledLog throttle(2.0, [fake] { return fake->t; });
  std::uint64_t n = 99;

  CHECK(throttle.allow("stale", &n));
  CHECK(n == 0);
  CHECK(throttle.allow("other", &n));  // keys are independent
  for (int k = 0; k < 5; ++k) {
    fake->t += 300ms;
    CHECK_FALSE(throttle.allow("stale"));
  }
  CHECK(throttle.suppressed("stale") == 5);
  CHECK(throttle.suppressed("other") == 0);
  CHECK(throttle.suppressed("never-seen") == 0);

  fake->t += 500ms;  // 2.0 s after the first emission
  CHECK(throttle.allow("stale", &n));
  CHECK(n == 5);
  CHECK_FALSE(throttle.allow("stale"));
  fake->t += 2s;
  CHECK(throttle.allow(std::string("stale"), &n));
  CHECK(n == 1);
  CHECK(throttle.suppressed("stale") == 6);
  CHECK(throttle.suppressed_total() == 6);

  CHECK_THROWS_AS(util::ThrottledLog(-1.0), std::invalid_argument);
  util::ThrottledLog zero(0.0, [fake] { return fake->t; });
  CHECK(zero.allow("k"));
  CHECK(zero.allow("k"));  // interval 0: never throttles
}

TEST_CASE("log lines carry role, id and level tag", "[util][log]") {
  util::log_init("agent", 3);
  CHECK(util::format_log_line(util::LogLevel::Info, "hello") == "[agent 3] hello\n");
  CHECK(util::format_log_line(util::LogLevel::Warn, "stale neighbour 5") ==
        "[agent 3] WARN stale neighbour 5\n");
  CHECK(util::format_log_line(util::LogLevel::Error, "boom\n") == "[agent 3] ERROR boom\n");
  util::log_init("supervisor");
  CHECK(util::format_log_line(util::LogLevel::Info, "") == "[supervisor] \n");
}

namespace {

// Runs fn with fd 2 redirected into a pipe and returns what was written there.
template <class F>
std::string capture_stderr(F&& fn) {
  int fds[2];
  REQUIRE(::pipe(fds) == 0);
  const int saved = ::dup(STDERR_FILENO);
  REQUIRE(saved >= 0);
  REQUIRE(::dup2(fds[1], STDERR_FILENO) >= 0);
  ::close(fds[1]);
  fn();
  ::dup2(saved, STDERR_FILENO);
  ::close(saved);
  std::string out;
  char buf[512];
  for (;;) {
    const ssize_t n = ::read(fds[0], buf, sizeof buf);
    if (n <= 0) break;
    out.append(buf, static_cast<std::size_t>(n));
  }
  ::close(fds[0]);
  return out;
}

}  // namespace

TEST_CASE("log writes whole lines to stderr, also from several threads", "[util][log]") {
  util::log_init("agent", 12);
  const std::string one = capture_stderr([] { util::log_warn("late tick"); });
  CHECK(one == "[agent 12] WARN late tick\n");

  auto fake = std::make_shared<FakeNow>();
  util::ThrottledLog throttle(1.0, [fake] { return fake->t; });
  const std::string throttled = capture_stderr([&] {
    CHECK(throttle.warn("k", "no data"));
    CHECK_FALSE(throttle.warn("k", "no data"));
    CHECK_FALSE(throttle.warn("k", "no data"));
    fake->t += 1s;
    CHECK(throttle.error("k", "no data"));
  });
  CHECK(throttled == "[agent 12] WARN no data\n[agent 12] ERROR no data (2 similar suppressed)\n");

  // 4 threads x 50 lines stay within a pipe's capacity (64 KiB), so no reader thread is needed.
  const std::string many = capture_stderr([] {
    std::vector<std::thread> threads;
    for (int t = 0; t < 4; ++t) {
      threads.emplace_back([t] {
        for (int k = 0; k < 50; ++k) {
          util::log_info("thread " + std::to_string(t) + " line " + std::to_string(k) +
                         " padding-padding-padding");
        }
      });
    }
    for (auto& th : threads) th.join();
  });
  std::size_t lines = 0;
  std::size_t pos = 0;
  while (pos < many.size()) {
    const std::size_t nl = many.find('\n', pos);
    REQUIRE(nl != std::string::npos);
    const std::string line = many.substr(pos, nl - pos);
    CHECK(line.rfind("[agent 12] thread ", 0) == 0);
    CHECK(line.size() >= 24);
    CHECK(line.compare(line.size() - 24, 24, " padding-padding-padding") == 0);
    ++lines;
    pos = nl + 1;
  }
  CHECK(lines == 200);
  util::log_init("shapeform");
}

TEST_CASE("stop flag: request_stop, reset_stop and SIGTERM", "[util][signals]") {
  util::reset_stop();
  CHECK_FALSE(util::stop_flag().load());
  util::request_stop();
  CHECK(util::stop_flag().load());
  CHECK(util::stop_signal() == 0);
  util::reset_stop();
  CHECK_FALSE(util::stop_flag().load());

  util::install_stop_signals();
  REQUIRE(std::raise(SIGTERM) == 0);  // handled synchronously in this thread
  CHECK(util::stop_flag().load());
  CHECK(util::stop_signal() == SIGTERM);
  util::reset_stop();

  util::install_stop_signals();  // re-arm (handlers are one-shot)
  REQUIRE(std::raise(SIGINT) == 0);
  CHECK(util::stop_flag().load());
  CHECK(util::stop_signal() == SIGINT);
  util::reset_stop();

  // Leave the process as we found it for the tests that follow.
  std::signal(SIGINT, SIG_DFL);
  std::signal(SIGTERM, SIG_DFL);
}

TEST_CASE("steady_ns follows steady_clock and never goes back", "[util][proc_stats]") {
  const auto before = std::chrono::duration_cast<std::chrono::nanoseconds>(
                          std::chrono::steady_clock::now().time_since_epoch())
                          .count();
  const std::int64_t a = util::steady_ns();
  const std::int64_t b = util::steady_ns();
  const auto after = std::chrono::duration_cast<std::chrono::nanoseconds>(
                         std::chrono::steady_clock::now().time_since_epoch())
                         .count();
  CHECK(before <= a);
  CHECK(a <= b);
  CHECK(b <= after);
}

TEST_CASE("rss_mb and CpuMeter give plausible numbers", "[util][proc_stats]") {
  const double rss = util::rss_mb();
  CHECK(std::isfinite(rss));
  CHECK(rss > 0.0);
  CHECK(rss < 1024.0 * 1024.0);

  util::CpuMeter meter;
  // Burn some CPU so the measured interval is not empty.
  volatile double sink = 0.0;
  const auto until = std::chrono::steady_clock::now() + 20ms;
  while (std::chrono::steady_clock::now() < until)
    sink = sink + std::sqrt(static_cast<double>(sink) + 1.0);
  const double pct = meter.percent();
  CHECK(std::isfinite(pct));
  CHECK(pct > 0.0);
  const double again = meter.percent();
  CHECK(std::isfinite(again));
  CHECK(again >= 0.0);
}

TEST_CASE("excerpt escapes control characters and keeps at most about max characters of long input", "[util][text]") {
  using shapeform::util::excerpt;
  CHECK(excerpt("plain text") == "plain text");
  CHECK(excerpt("a\nb\tc\rd\x01" "e\x7f") == "a\\nb\\tc\\rd\\x01e\\x7f");
  const std::string huge = "BEGIN" + std::string(1'000'000, 'x') + "END";
  const std::string e = excerpt(huge);
  CHECK(e.size() <= shapeform::util::kQuoteMax + 20);
  CHECK(e.rfind("BEGIN", 0) == 0);  // the beginning and the end are kept
  CHECK(e.size() >= 3);
  CHECK(e.compare(e.size() - 3, 3, "END") == 0);
  CHECK(e.find("[... " + std::to_string(huge.size() - 120 - 50) + " characters ...]") != std::string::npos);
  CHECK(excerpt(std::string(200, 'y')) == std::string(200, 'y'));  // up to max: as it is
  CHECK(excerpt(std::string(201, 'y')).size() < 240);
  CHECK(excerpt(huge, 40).size() < 80);
}

TEST_CASE("bounded_line keeps a short line as it is and shortens a long one", "[util][text]") {
  using shapeform::util::bounded_line;
  CHECK(bounded_line("two\nlines") == "two\nlines");
  const std::string long_line = "console: unknown command '" + std::string(5000, 'w') + "'";
  const std::string b = bounded_line(long_line);
  CHECK(b.size() <= shapeform::util::kLineMax + 20);
  CHECK(b.rfind("console: unknown command 'www", 0) == 0);
  CHECK(b.back() == '\'');
}

TEST_CASE("regenerate_blocks replaces what lies between the markers and keeps the rest", "[util][text]") {
  const auto gen = [](const std::string& section) { return "[" + section + "]\n"; };
  const std::string md = "intro\n<!-- BEGIN GENERATED t: a -->\nold\nlines\n<!-- END GENERATED -->\nmid\n"
                         "<!-- BEGIN GENERATED t: b -->\n<!-- END GENERATED -->\nend\n";
  const std::string want = "intro\n<!-- BEGIN GENERATED t: a -->\n[a]\n<!-- END GENERATED -->\nmid\n"
                           "<!-- BEGIN GENERATED t: b -->\n[b]\n<!-- END GENERATED -->\nend\n";
  CHECK(util::regenerate_blocks(md, "BEGIN GENERATED t: ", "END GENERATED", gen) == want);
  CHECK(util::regenerate_blocks(want, "BEGIN GENERATED t: ", "END GENERATED", gen) == want);  // a fixed point
  // A shell comment marker: the end marker's whole line stays, indentation included.
  const std::string sh = "x\n# BEGIN GENERATED t: rules\nold\n  # END GENERATED\ny\n";
  CHECK(util::regenerate_blocks(sh, "BEGIN GENERATED t: ", "END GENERATED", gen) ==
        "x\n# BEGIN GENERATED t: rules\n[rules]\n  # END GENERATED\ny\n");
  CHECK(util::regenerate_blocks("no markers\n", "BEGIN GENERATED t: ", "END GENERATED", gen) == "no markers\n");
  CHECK_THROWS_AS(util::regenerate_blocks("# BEGIN GENERATED t: a\nold\n", "BEGIN GENERATED t: ", "END GENERATED", gen),
                  std::invalid_argument);
  CHECK_THROWS_AS(util::regenerate_blocks("# BEGIN GENERATED t: -->\n# END GENERATED\n", "BEGIN GENERATED t: ",
                                          "END GENERATED", gen),
                  std::invalid_argument);
}

TEST_CASE("PhaseClock books each lap to the phase that ended and means per tick", "[util][stats]") {
  shapeform::util::PhaseClock<3> clock({"a", "b", "c"});
  CHECK(clock.mean_us(0) == 0.0);
  // Tick 1: a 1000 ns, b 3000 ns, c 0; tick 2: a 3000 ns, b 1000 ns, c 2000 ns.
  clock.start_at(10'000);
  clock.lap_at(0, 11'000);
  clock.lap_at(1, 14'000);
  clock.lap_at(2, 14'000);
  clock.start_at(100'000);
  clock.lap_at(0, 103'000);
  clock.lap_at(1, 104'000);
  clock.lap_at(2, 106'000);
  CHECK(clock.ticks() == 2);
  CHECK(clock.mean_us(0) == Approx(2.0));
  CHECK(clock.mean_us(1) == Approx(2.0));
  CHECK(clock.mean_us(2) == Approx(1.0));
  CHECK(clock.line() == "a 2.0 us, b 2.0 us, c 1.0 us, total 5.0 us per tick over 2 ticks");
}

TEST_CASE("IdMap holds what std::map holds, in ascending ids, under random inserts, updates and erasures", "[util]") {
  std::mt19937 rng(7);
  std::uniform_int_distribution<int> id(0, 300), op(0, 11);
  util::IdMap<int> flat;
  std::map<std::int32_t, int> tree;
  for (int step = 0; step < 20000; ++step) {
    const std::int32_t k = id(rng);
    const int o = op(rng);
    if (o < 6) {
      flat[k] += step;
      tree[k] += step;
    } else if (o < 8) {
      REQUIRE(flat.erase(k) == tree.erase(k));
    } else if (o == 10) {
      REQUIRE(flat.insert_or_assign(k, step) == step);
      tree[k] = step;
    } else if (o == 11 && step % 50 == 0) {
      // Every value divisible by the id's last digit plus 2 goes, in one pass.
      const auto doomed = [](std::int32_t key, int value) { return value % (key % 10 + 2) == 0; };
      std::size_t gone = 0;
      for (auto it = tree.begin(); it != tree.end();)
        if (doomed(it->first, it->second)) it = tree.erase(it), ++gone;
        else ++it;
      REQUIRE(flat.erase_if([&](const auto& p) { return doomed(p.first, p.second); }) == gone);
    } else {
      REQUIRE(flat.contains(k) == (tree.count(k) == 1));
      REQUIRE((flat.find(k) == flat.end()) == (tree.find(k) == tree.end()));
      if (tree.count(k) == 1) REQUIRE(flat.at(k) == tree.at(k));
      else REQUIRE_THROWS_AS(flat.at(k), std::out_of_range);
    }
    if (step % 997 == 0) {
      REQUIRE(std::vector<std::pair<std::int32_t, int>>(flat.begin(), flat.end()) ==
              std::vector<std::pair<std::int32_t, int>>(tree.begin(), tree.end()));
    }
  }
  REQUIRE(flat.size() == tree.size());
  REQUIRE(std::vector<std::pair<std::int32_t, int>>(flat.begin(), flat.end()) ==
          std::vector<std::pair<std::int32_t, int>>(tree.begin(), tree.end()));
}

TEST_CASE("IdMap refuses a negative id and finds none", "[util]") {
  util::IdMap<int> m;
  m[3] = 1;
  REQUIRE(m.find(-1) == m.end());
  REQUIRE_FALSE(m.contains(-5));
  REQUIRE_THROWS_AS(m[-1], std::out_of_range);
  REQUIRE(m.size() == 1);
  m.clear();
  REQUIRE(m.empty());
  REQUIRE(m.find(3) == m.end());
}
