/// Event-triggered primitives: envelopes, gust trains, turbulence, gravity and head motions against
/// their definitions (numbers from the parameters, not from the code).
#include "hair_sim/core/events/EventSchedule.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "TestUtil.hpp"
#include "hair_sim/tools/Scenario.hpp"

namespace hair_sim {
namespace {

constexpr double kPi = 3.14159265358979323846;
const Vec3 kG(0.0, 0.0, -9.81);

Event gust(std::uint64_t seed) {
  Event e;
  e.type = EventType::WindGust;
  e.start = 1.0;
  e.vector = Vec3(0.0, 3.0, 0.0);  // mean 3 m/s along +y
  e.peak = 6.0;
  e.period = 2.0;
  e.jitter = 0.3;
  e.seed = seed;
  return e;
}

TEST(EventScheduleTest, GustTrainHasItsMeanPeakBaseAndTiming) {
  const Event e = gust(7);
  EventSchedule s;
  s.add(e);
  const double base = (4.0 * 3.0 - 6.0) / 3.0;  // between gusts: 2 m/s
  const int periods = 400;
  const double dt = 1e-3;
  double sum = 0.0, lowest = 1e9, highest = 0.0;
  long samples = 0;
  for (double t = e.start; t < e.start + periods * e.period; t += dt, ++samples) {
    const Vec3 v = s.sample(t, kG).wind;
    EXPECT_NEAR(v.x(), 0.0, 1e-12);  // along the mean's direction only
    sum += v.y();
    lowest = std::min(lowest, v.y());
    highest = std::max(highest, v.y());
  }
  EXPECT_NEAR(sum / samples, 3.0, 0.01 * 3.0);  // time average = mean within 1 %
  EXPECT_NEAR(lowest, base, 1e-9);
  EXPECT_NEAR(highest, 6.0, 1e-4);
  for (long k = 0; k < periods; ++k) {
    // Crest k within +-jitter/2 periods of the middle of its period, at the peak speed; a quarter
    // period either side of it the gust is over (base speed), whatever the jitter.
    const double crest = EventSchedule::gustCrest(e, k);
    const double middle = e.start + (k + 0.5) * e.period;
    ASSERT_LE(std::abs(crest - middle), 0.5 * e.jitter * e.period + 1e-12) << k;
    EXPECT_NEAR(s.sample(crest, kG).wind.y(), 6.0, 1e-9) << k;
    EXPECT_NEAR(s.sample(crest + 0.25 * e.period, kG).wind.y(), base, 1e-9) << k;
  }
}

TEST(EventScheduleTest, SameSeedSameRunDifferentSeedsDiffer) {
  EventSchedule a, b, c;
  a.add(gust(7));
  b.add(gust(7));
  c.add(gust(8));
  Event turbulence;
  turbulence.type = EventType::Turbulence;
  turbulence.intensity = 1.0;
  turbulence.seed = 7;
  a.add(turbulence);
  b.add(turbulence);
  turbulence.seed = 8;
  c.add(turbulence);
  double differ = 0.0;
  for (double t = 0.0; t < 20.0; t += 0.01) {
    const EventSample sa = a.sample(t, kG), sb = b.sample(t, kG), sc = c.sample(t, kG);
    const Vec3 p(0.1 * t, 0.2, 1.6);
    ASSERT_EQ(sa.wind, sb.wind);
    ASSERT_EQ(sa.turbulence.at(p), sb.turbulence.at(p));
    differ =
        std::max(differ, (sa.wind - sc.wind).norm() + (sa.turbulence.at(p) - sc.turbulence.at(p)).norm());
  }
  EXPECT_GT(differ, 0.5);
  EXPECT_NE(EventSchedule::gustCrest(gust(7), 3), EventSchedule::gustCrest(gust(8), 3));
}

TEST(EventScheduleTest, EnvelopeEasesInAndOutAndHandsOver) {
  EventSchedule s;
  Event wind;
  wind.type = EventType::Wind;
  wind.start = 2.0;
  wind.duration = 4.0;
  wind.ease = 1.0;
  wind.vector = Vec3(2.0, 0.0, 0.0);
  s.add(wind);
  EXPECT_EQ(s.sample(1.999, kG).wind.x(), 0.0);
  EXPECT_NEAR(s.sample(2.5, kG).wind.x(), 1.0, 1e-12);  // half way through the ease: 0.5 - 0.5 cos(pi/2)
  EXPECT_NEAR(s.sample(4.0, kG).wind.x(), 2.0, 1e-12);
  EXPECT_NEAR(s.sample(5.5, kG).wind.x(), 1.0, 1e-12);
  EXPECT_EQ(s.sample(6.0, kG).wind.x(), 0.0);
  // Overlapping winds add.
  Event more = wind;
  more.vector = Vec3(0.0, 1.0, 0.0);
  s.add(more);
  EXPECT_NEAR((s.sample(4.0, kG).wind - Vec3(2.0, 1.0, 0.0)).norm(), 0.0, 1e-12);
  // Duration 0: until the next of its type, which takes over during its own ease.
  EventSchedule h;
  Event up;
  up.type = EventType::Gravity;
  up.start = 1.0;
  up.vector = Vec3(0.0, 0.0, 9.81);
  h.add(up);
  Event side = up;
  side.start = 3.0;
  side.ease = 2.0;
  side.vector = Vec3(9.81, 0.0, 0.0);
  h.add(side);
  EXPECT_EQ(h.sample(0.5, kG).gravity, kG);
  EXPECT_EQ(h.sample(2.0, kG).gravity, up.vector);
  EXPECT_NEAR((h.sample(4.0, kG).gravity - 0.5 * (up.vector + side.vector)).norm(), 0.0, 1e-12);
  EXPECT_NEAR((h.sample(5.0, kG).gravity - side.vector).norm(), 0.0, 1e-12);
  EXPECT_EQ(h.end(0), 5.0);
  h.dropEndedBefore(6.0);
  EXPECT_EQ(h.size(), 1u);
  EXPECT_NEAR((h.sample(7.0, kG).gravity - side.vector).norm(), 0.0, 1e-12);
}

// The node refuses an event that would be over before the hair's time gets to it: endIfAdded is the end
// the event would have once added (as end() gives then), without adding it.
TEST(EventScheduleTest, EndIfAddedIsTheEndOnceAdded) {
  EventSchedule s;
  Event calm;
  calm.type = EventType::Wind;
  calm.start = 10.0;
  calm.ease = 0.5;
  s.add(calm);
  Event early = calm;  // until replaced, but calm (at 10 s) replaces it
  early.start = 1.0;
  early.vector = Vec3(3.0, 0.0, 0.0);
  Event gravity;  // another type: not replaced by a wind
  gravity.type = EventType::Gravity;
  gravity.start = 1.0;
  Event later = calm;
  later.start = 12.0;
  Event timed = early;
  timed.duration = 2.0;
  EXPECT_EQ(s.endIfAdded(early), 10.5);
  EXPECT_TRUE(std::isinf(s.endIfAdded(gravity)));
  EXPECT_TRUE(std::isinf(s.endIfAdded(later)));
  EXPECT_EQ(s.endIfAdded(timed), 3.0);
  Event same = calm;  // the same start: added after calm, so nothing replaces it
  EXPECT_TRUE(std::isinf(s.endIfAdded(same)));
  for (const Event& e : {early, gravity, later, timed, same}) {
    EventSchedule t = s;
    const double expected = t.endIfAdded(e);
    t.add(e);
    bool found = false;
    for (std::size_t i = 0; i < t.size(); ++i)
      if (t.event(i).start == e.start && t.event(i).type == e.type && t.event(i).vector == e.vector &&
          t.event(i).duration == e.duration && (i + 1 == t.size() || t.event(i + 1).start > e.start)) {
        EXPECT_EQ(t.end(i), expected) << eventTypeName(e.type) << " at " << e.start;
        found = true;
      }
    EXPECT_TRUE(found);
  }
}

// The node bounds the turbulence events acting together (each adds 16 plane waves to every segment's wind
// at every substep): countOverlapping counts those of the type that act while a new one would.
TEST(EventScheduleTest, CountOverlappingCountsTheEventsOfItsTypeActingWhileItWould) {
  EventSchedule s;
  Event t;
  t.type = EventType::Turbulence;
  t.intensity = 0.1;
  t.duration = 10.0;
  for (int k = 0; k < 3; ++k) {  // [0, 10), [5, 15), [10, 20)
    t.start = 5.0 * k;
    s.add(t);
  }
  Event wind;  // another type: not counted
  wind.start = 0.0;
  s.add(wind);
  Event probe = t;
  probe.start = 11.0;
  probe.duration = 1.0;
  EXPECT_EQ(s.countOverlapping(probe), 2u);  // [5, 15) and [10, 20)
  probe.start = 9.5;
  EXPECT_EQ(s.countOverlapping(probe), 3u);
  probe.start = 20.0;  // [10, 20) has ended when it starts
  EXPECT_EQ(s.countOverlapping(probe), 0u);
  probe.start = 0.0;
  probe.duration = 100.0;
  EXPECT_EQ(s.countOverlapping(probe), 3u);
  // Until replaced: a later one of the type ends it (after its ease); it ends an earlier one likewise.
  EventSchedule r;
  Event steady = t;
  steady.duration = 0.0;
  steady.start = 0.0;
  r.add(steady);
  Event next = steady;
  next.start = 4.0;
  EXPECT_EQ(r.countOverlapping(next), 0u);  // replaces `steady` at once (no ease)
  next.ease = 1.0;
  EXPECT_EQ(r.countOverlapping(next), 1u);  // both act during its ease
  next.start = 0.0;
  next.ease = 0.0;
  EXPECT_EQ(r.countOverlapping(next), 0u);
  r.add(Event(next));
  Event timed = t;
  timed.start = 2.0;
  timed.duration = 1.0;
  EXPECT_EQ(r.countOverlapping(timed), 0u);  // any later one of its type replaces the steady one
  timed.ease = 0.5;
  EXPECT_EQ(r.countOverlapping(timed), 1u);  // during its ease
}

TEST(EventScheduleTest, TurbulenceHasItsIntensityAndNoDivergence) {
  Event e;
  e.type = EventType::Turbulence;
  e.intensity = 0.8;
  e.length_scale = 0.3;
  e.time_scale = 0.5;
  EventSchedule s;
  s.add(e);
  // RMS per component over many points and times: the intensity (the waves' random orientations
  // make it exact only on average; 16 waves over 64 seeds stay within 10 %).
  double sum2 = 0.0;
  long n = 0;
  for (std::uint64_t seed = 1; seed <= 64; ++seed) {
    EventSchedule one;
    e.seed = seed;
    one.add(e);
    for (double t = 0.0; t < 10.0; t += 0.37) {
      const EventSample sample = one.sample(t, kG);
      for (int i = 0; i < 4; ++i) {
        sum2 += sample.turbulence.at(Vec3(0.11 * i, -0.07 * i, 1.6)).squaredNorm();
        n += 3;
      }
    }
  }
  EXPECT_NEAR(std::sqrt(sum2 / n), 0.8, 0.08);
  // Divergence-free (each wave's amplitude is perpendicular to its wave vector): central differences.
  const EventSample sample = s.sample(1.3, kG);
  const double h = 1e-5;
  for (const Vec3& p : {Vec3(0, 0, 1.6), Vec3(0.2, -0.1, 1.5), Vec3(-0.3, 0.4, 1.2)}) {
    double div = 0.0, scale = 0.0;
    for (int a = 0; a < 3; ++a) {
      const Vec3 d = Vec3::Unit(a) * h;
      const double derivative = (sample.turbulence.at(p + d)[a] - sample.turbulence.at(p - d)[a]) / (2 * h);
      div += derivative;
      scale += std::abs(derivative);
    }
    EXPECT_LT(std::abs(div), 1e-6 * (1.0 + scale)) << p.transpose();
  }
  // Smooth in time: one millisecond changes it by far less than the intensity.
  const Vec3 p(0.1, 0.1, 1.6);
  EXPECT_LT((s.sample(2.0, kG).turbulence.at(p) - s.sample(2.001, kG).turbulence.at(p)).norm(), 0.05);
}

// hair_sim_node's ~wind_scale multiplies all the wind: the uniform one and the turbulence field.
TEST(EventScheduleTest, TurbulenceFieldScales) {
  EventSchedule s;
  Event e;
  e.type = EventType::Turbulence;
  e.intensity = 2.0;
  s.add(e);
  WindField field = s.sample(1.0, kG).turbulence;
  const Vec3 p(0.1, -0.2, 1.5), v = field.at(p);
  ASSERT_GT(v.norm(), 0.0);
  field.scale(0.5);
  EXPECT_NEAR((field.at(p) - 0.5 * v).norm(), 0.0, 1e-15);
  field.scale(0.0);
  EXPECT_EQ(field.at(p), Vec3::Zero());
}

TEST(EventScheduleTest, HeadMotionsTurnByTheirAmplitudeAtTheirFrequencyAndCompose) {
  Event shake;
  shake.type = EventType::Shake;
  shake.start = 1.0;
  shake.amplitude = 0.5;
  shake.frequency = 2.0;
  EventSchedule s;
  s.add(shake);
  // yaw = A sin(2 pi f (t - start)): A at a quarter period, 0 at a half, -A at three quarters.
  auto yaw = [&](double t) {
    const Mat3 r = s.sample(t, kG).head_rotation;
    return std::atan2(r(1, 0), r(0, 0));
  };
  EXPECT_NEAR(yaw(1.125), 0.5, 1e-12);
  EXPECT_NEAR(yaw(1.25), 0.0, 1e-12);
  EXPECT_NEAR(yaw(1.375), -0.5, 1e-12);
  EXPECT_NEAR(yaw(1.625), 0.5, 1e-12);
  // A nod on top: the rotations compose in order of start (yaw, then pitch about the turned y).
  Event nod;
  nod.type = EventType::Nod;
  nod.start = 1.0;
  nod.amplitude = 0.3;
  nod.frequency = 2.0;
  s.add(nod);
  const Mat3 expected =
      (Eigen::AngleAxisd(0.5, Vec3::UnitZ()) * Eigen::AngleAxisd(0.3, Vec3::UnitY())).toRotationMatrix();
  EXPECT_TRUE(s.sample(1.125, kG).head_rotation.isApprox(expected, 1e-12));
  // A turn holds its angle; a tilt rolls.
  EventSchedule t;
  Event turn;
  turn.type = EventType::Turn;
  turn.amplitude = -0.7;
  turn.ease = 0.5;
  t.add(turn);
  EXPECT_TRUE(t.sample(3.0, kG).head_rotation.isApprox(
      Eigen::AngleAxisd(-0.7, Vec3::UnitZ()).toRotationMatrix(), 1e-12));
  Event tilt;
  tilt.type = EventType::Tilt;
  tilt.amplitude = 0.2;
  tilt.frequency = 1.0;
  EventSchedule u;
  u.add(tilt);
  EXPECT_TRUE(u.sample(0.25, kG).head_rotation.isApprox(
      Eigen::AngleAxisd(0.2, Vec3::UnitX()).toRotationMatrix(), 1e-12));
  EXPECT_TRUE(isHeadMotion(EventType::Tilt));
  EXPECT_FALSE(isHeadMotion(EventType::Gravity));
}

TEST(EventScheduleTest, BadEventsAreNamed) {
  Event e = gust(1);
  e.peak = 20.0;  // more than 4 x the mean
  EXPECT_NE(test::errorOf([&] { EventSchedule().add(e, "msg"); }).find("peak: 20"), std::string::npos);
  e = gust(1);
  e.duration = 1.0;
  e.ease = 0.8;
  EXPECT_NE(test::errorOf([&] { EventSchedule().add(e, "msg"); }).find("ease: 0.8"), std::string::npos);
  e = gust(1);
  e.vector = Vec3(NAN, 0, 0);
  EXPECT_NE(test::errorOf([&] { EventSchedule().add(e, "msg"); }).find("mean: [nan"), std::string::npos);
  Event w;
  w.start = -1.0;
  EXPECT_NE(test::errorOf([&] { EventSchedule().add(w, "msg"); }).find("start: -1"), std::string::npos);
  w.start = 0.0;
  w.vector = Vec3(0, 0, INFINITY);
  EXPECT_NE(test::errorOf([&] { EventSchedule().add(w, "msg"); }).find("velocity: [0, 0, inf]"),
            std::string::npos);
  // Each check by its field and value, "<type> event: <field>: <value> ..."; where cheap, a value just
  // inside the limit is accepted, so that the limit itself is pinned.
  auto add = [](const Event& event) { EventSchedule().add(event, "msg"); };
  w = Event();
  w.duration = -2.5;
  test::expectInvalid([&] { add(w); }, "wind event: duration: -2.5");
  e = gust(1);
  e.period = 1e-3;
  EXPECT_NO_THROW(add(e));
  e.period = 5e-4;
  test::expectInvalid([&] { add(e); }, "wind_gust event: period: 0.0005");
  e = gust(1);
  e.vector = Vec3::Zero();  // no mean speed: no direction for the gusts
  test::expectInvalid([&] { add(e); }, "wind_gust event: mean: [0, 0, 0]");
  Event t;
  t.type = EventType::Turbulence;
  t.intensity = 1.0;
  t.length_scale = 1e-3;
  EXPECT_NO_THROW(add(t));
  t.length_scale = 2e-4;
  test::expectInvalid([&] { add(t); }, "turbulence event: length_scale: 0.0002");
  t.length_scale = 0.5;
  t.time_scale = 1000.0;
  EXPECT_NO_THROW(add(t));
  t.time_scale = 2000.0;
  test::expectInvalid([&] { add(t); }, "turbulence event: time_scale: 2000");
  Event g;
  g.type = EventType::Gravity;
  g.vector = Vec3(60.0, 0.0, 80.0);  // exactly 100 m/s^2
  EXPECT_NO_THROW(add(g));
  g.vector = Vec3(0.0, 0.0, -101.0);
  test::expectInvalid([&] { add(g); }, "gravity event: acceleration: [0, 0, -101]");
  // Nod, shake and tilt swing within +-pi/2 rad (1.5708 rad); a turn holds within +-pi rad.
  for (EventType type : {EventType::Nod, EventType::Shake, EventType::Tilt}) {
    Event h;
    h.type = type;
    const std::string name = eventTypeName(type);
    for (double amplitude : {1.57, -1.57}) {
      h.amplitude = amplitude;
      EXPECT_NO_THROW(add(h)) << name << " " << amplitude;
    }
    h.amplitude = 1.58;
    test::expectInvalid([&] { add(h); }, name + " event: amplitude: 1.58");
    h.amplitude = -1.58;
    test::expectInvalid([&] { add(h); }, name + " event: amplitude: -1.58");
  }
  Event turn;
  turn.type = EventType::Turn;
  for (double amplitude : {3.0, -3.0}) {
    turn.amplitude = amplitude;
    EXPECT_NO_THROW(add(turn)) << amplitude;
  }
  turn.amplitude = 3.2;
  test::expectInvalid([&] { add(turn); }, "turn event: amplitude: 3.2");
  turn.amplitude = -3.2;
  test::expectInvalid([&] { add(turn); }, "turn event: amplitude: -3.2");
}

TEST(EventScheduleTest, MalformedEventsInAScenarioAreNamed) {
  const std::string good =
      "duration: 2.0\noutput_rate: 30\nhead:\n  - {t: 0.0, position: [0, 0, 1.6], rpy: [0, 0, 0]}\n"
      "events:\n"
      "  - {type: wind, start: 0.5, ease: 0.2, velocity: [1, 0, 0]}\n"
      "  - {type: wind_gust, start: 1, mean: [2, 0, 0], peak: 3, period: 1.5, jitter: 0.2, seed: 4}\n"
      "  - {type: turbulence, start: 0, intensity: 0.5, length_scale: 0.2, time_scale: 0.4, seed: 1}\n"
      "  - {type: gravity, start: 1, duration: 1, ease: 0.5, acceleration: [0, 0, 9.81]}\n"
      "  - {type: shake, start: 0, duration: 2, ease: 0.5, amplitude: 0.5, frequency: 2}\n"
      "  - {type: turn, start: 0, amplitude: 0.5}\n";
  const std::string path = test::writeTemp("events.yaml", good);
  const Scenario s = Scenario::load(path);
  ASSERT_EQ(s.events.size(), 6u);
  EXPECT_EQ(s.events[1].type, EventType::WindGust);
  EXPECT_EQ(s.events[1].seed, 4u);
  EXPECT_EQ(s.schedule().size(), 6u);
  const std::vector<test::FileEdit> cases = {
      {"type: wind,", "type: breeze,", "events[0].type", "'breeze'"},
      {"velocity: [1, 0, 0]", "velocity: [1, 0]", "events[0].velocity", "[1, 0]"},
      {"velocity: [1, 0, 0]", "velocity: [1, 0, 0], peak: 2", "events[0].peak", "unknown key"},
      {"peak: 3,", "peak: 30,", "events[1].peak", "30"},
      {"jitter: 0.2", "jitter: 0.9", "events[1].jitter", "0.9"},
      {"intensity: 0.5", "intensity: -1", "events[2].intensity", "-1"},
      {"ease: 0.5, acceleration", "ease: 0.7, acceleration", "events[3].ease", "0.7"},
      {"frequency: 2}", "frequency: .inf}", "events[4].frequency", ".inf"},
      {"turn, start: 0, amplitude: 0.5", "turn, start: 0, amplitude: 0.5, frequency: 1",
       "events[5].frequency", "unknown key"},
      {"start: 0.5, ease: 0.2", "start: -0.5, ease: 0.2", "events[0].start", "-0.5"},
  };
  test::expectEditsNamed(good, cases, [](const std::string& p) { Scenario::load(p); });
}

}  // namespace
}  // namespace hair_sim
