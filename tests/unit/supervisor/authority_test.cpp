// The command authority: the epoch of each command this supervisor publishes, learning a rival's
// command, refusing absurd epochs, and the model clock of the epoch in force.
#include <catch2/catch.hpp>

#include "supervisor_rig.hpp"

using namespace shapeform;
using namespace shapeform::test;

namespace {

core::CompiledCommand ellipse() {
  core::Command c;
  c.shape.kind = core::ShapeKind::Ellipse;
  return core::compile(c);
}

}  // namespace

TEST_CASE("authority: each command it publishes takes the next epoch, as its own",
          "[supervisor][authority]") {
  Rig r;
  CHECK(r.authority.epoch() == 0);
  CHECK_FALSE(r.authority.own());
  r.authority.publish(circle(), 0);
  r.authority.publish(ellipse(), kS);
  REQUIRE(r.sent.size() == 2);
  CHECK(r.sent[0].id == dds::CommandId{1, source(0x10)});
  CHECK(r.sent[1].id == dds::CommandId{2, source(0x10)});
  CHECK(r.sent[1].issuer_name == "test supervisor");
  CHECK(r.authority.own());
  CHECK(r.authority.current().shape.kind == core::ShapeKind::Ellipse);
  CHECK(r.monitor.command_id() == r.sent[1].id);  // the metrics measure against it
  const auto events = r.take_events();
  REQUIRE(events.size() == 2);
  CHECK(events[1]["event"] == "epoch");
  CHECK(events[1]["epoch"] == 2);
  CHECK(events[1]["own"] == true);
  CHECK(events[1]["shape"] == "ellipse");
  CHECK(r.take_human().find("epoch 2: ellipse") != std::string::npos);
}

TEST_CASE("authority: a command continues after the epochs the agents follow", "[supervisor][authority]") {
  Rig r;
  r.follow(3, 4.0, dds::CommandId{7, source(0x30)}, 0.0, 0);  // a previous supervisor's epoch 7
  CHECK(r.authority.foreign_in_force(0));                     // `start` keeps it
  r.authority.publish(circle(), 0);
  REQUIRE(r.sent.size() == 1);
  CHECK(r.sent[0].id.epoch == 8);
  CHECK_FALSE(r.authority.foreign_in_force(0));  // it commands now
}

TEST_CASE("authority: a rival's greater epoch is learnt, and the next command goes after it",
          "[supervisor][authority]") {
  Rig r;
  r.authority.publish(circle(), 0);
  r.take_events();
  CHECK(r.authority.hear(rival(ellipse(), 5), 0, kS));
  CHECK_FALSE(r.authority.own());
  CHECK(r.authority.epoch() == 5);
  CHECK(r.authority.current().shape.kind == core::ShapeKind::Ellipse);
  CHECK(r.authority.superseded() == 1);
  CHECK(r.authority.publisher() == "rival [" + dds::to_string(source(0x20)) + "]");
  CHECK(r.monitor.command_id() == dds::CommandId{5, source(0x20)});
  CHECK(r.take_human().find("epoch 1 of this supervisor was superseded by epoch 5 of rival") !=
        std::string::npos);
  const auto events = r.take_events();
  REQUIRE(events.size() == 1);
  CHECK(events[0]["event"] == "in_force");
  CHECK(events[0]["superseded"] == 1);
  CHECK(events[0]["own"] == false);
  // An older or the same command changes nothing; the next own command is epoch 6.
  CHECK_FALSE(r.authority.hear(rival(circle(), 4, 0x30), 0, kS));
  CHECK_FALSE(r.authority.hear(rival(ellipse(), 5), 0, kS));
  r.authority.publish(circle(), 2 * kS);
  CHECK(r.sent.back().id == dds::CommandId{6, source(0x10)});
  CHECK(r.authority.own());
}

TEST_CASE("authority: on the same epoch the greater issuer wins", "[supervisor][authority]") {
  Rig r;
  r.authority.publish(circle(), 0);  // epoch 1 of issuer 0x10
  CHECK_FALSE(r.authority.hear(rival(ellipse(), 1, 0x05), 0, kS));
  CHECK(r.authority.own());
  CHECK(r.authority.hear(rival(ellipse(), 1, 0x20), 0, kS));
  CHECK(r.authority.id() == dds::CommandId{1, source(0x20)});
}

TEST_CASE("authority: an absurd epoch jump is refused, counted, and reported throttled when repeated",
          "[supervisor][authority]") {
  Rig r;
  r.authority.publish(circle(), 0);
  r.take_events();
  const std::uint64_t absurd = 2 + dds::kMaxEpochJump;
  for (int i = 0; i < 3; ++i) CHECK_FALSE(r.authority.hear(rival(ellipse(), absurd), 0, kS));
  CHECK(r.authority.own());
  CHECK(r.authority.commands_refused() == 3);
  auto events = r.take_events();
  REQUIRE(events.size() == 2);  // the new epoch, then its repetitions at most once per 5 s
  CHECK(events[0]["event"] == "rejected");
  CHECK(events[0]["epoch"] == absurd);
  CHECK(r.authority.hear(rival(ellipse(), absurd + 1), 0, kS) == false);
  CHECK(r.take_events().size() == 1);  // another epoch is reported at once
  r.authority.refuse_invalid(9, "shape.r0: must be > 0");
  CHECK(r.authority.commands_refused() == 5);
  CHECK_FALSE(r.authority.recheck(0, kS));  // still absurd from epoch 1
  r.authority.publish(circle(), 2 * kS);
  CHECK(r.sent.back().id.epoch == 2);  // the refused epoch does not move the next one
}

TEST_CASE("authority: model time runs at the agents' rate times dt, and stands still while held",
          "[supervisor][authority]") {
  core::CompiledCommand c = circle();
  c.dt = 0.5;
  Rig r(c);
  CHECK(r.authority.model_time(5 * kS) == 0.0);  // no command in force yet
  r.authority.publish(c, kS);
  CHECK(r.authority.model_time(3 * kS) == Approx(2 * Rig::kAgentRateHz * 0.5));
  CHECK(r.authority.since_epoch_s(3 * kS) == Approx(2.0));
  c.hold = true;
  r.authority.publish(c, 3 * kS);
  CHECK(r.authority.model_time(9 * kS) == 0.0);
}

TEST_CASE("authority: a learnt command's clock is taken from the agents that follow it",
          "[supervisor][authority]") {
  Rig r;
  REQUIRE(r.authority.hear(rival(circle(), 3), 0, 10 * kS));
  CHECK(r.authority.model_time(10 * kS) == 0.0);
  r.follow(4, 4.0, dds::CommandId{3, source(0x20)}, 40.0, 10 * kS);  // the agents are at model time 40
  r.authority.sync_clock(10 * kS);
  CHECK(r.authority.model_time(10 * kS) == Approx(40.0));
  CHECK(r.authority.model_time(11 * kS) == Approx(40.0 + Rig::kAgentRateHz * circle().dt));
}

TEST_CASE("authority: after a rebuild only its own command is offered again", "[supervisor][authority]") {
  Rig r;
  r.authority.republish();
  CHECK(r.sent.empty());  // nothing in force
  r.authority.publish(circle(), 0);
  r.authority.republish();
  REQUIRE(r.sent.size() == 2);
  CHECK(r.sent[1].id == r.sent[0].id);
  REQUIRE(r.authority.hear(rival(circle(), 4), 0, kS));
  r.authority.republish();
  CHECK(r.sent.size() == 2);
}
