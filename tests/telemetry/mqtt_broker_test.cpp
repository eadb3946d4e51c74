// `cncore serve --mqtt` against a real Mosquitto broker started by the test on a free loopback
// port, read with `mosquitto_sub`: a served program's events arrive in order with the served
// cycle time, samples follow the tool, the last will fires when the controller is killed, TLS
// with a CA made here works, and a wrong password is refused at start.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "mqtt_harness.hpp"

namespace {

using namespace mqtt_test;
using nlohmann::json;

// Stops at M0 after the first line: the served run passes through FEED_HOLD.
constexpr const char* kProgram =
    "G21 G90 G17 G94\n"
    "N10 G1 X30 Y0 F6000\n"
    "N20 M0\n"
    "N30 G1 X30 Y20\n"
    "N40 M30\n";

class MqttBroker : public ::testing::Test {
 protected:
  void SetUp() override {
    for (const char* p :
         {"mosquitto", "mosquitto_sub", "mosquitto_pub", "mosquitto_passwd", "openssl"}) {
      ASSERT_FALSE(find_program(p).empty()) << p << " is not installed (make deps installs it)";
    }
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    dir = fs::path(CNCORE_TEST_TMP_DIR) / (std::string("mqtt-") + info->name());
    fs::remove_all(dir);
    fs::create_directories(dir);
    write_text(dir / "part.ngc", kProgram);
  }

  // `cncore serve` of part.ngc, started at once, with the console lines given.
  std::vector<std::string> serve_args(const std::string& url) const {
    return {CNCORE_BIN,      "serve",     "--no-state",
            "--no-realtime", "--program", (dir / "part.ngc").string(),
            "--start",       "--mqtt",    url};
  }

  fs::path dir;
};

// The subscriber's messages as "leaf:key" (state: execution, cycle: event, online: yes/no),
// consecutive repeats of a state merged; samples left out.
std::vector<std::string> sequence(const std::vector<Received>& ms) {
  std::vector<std::string> out;
  for (const Received& m : ms) {
    const json j = json::parse(m.payload);
    const std::string leaf = m.topic.substr(m.topic.rfind('/') + 1);
    std::string key;
    if (leaf == "state") key = "state:" + j["execution"].get<std::string>();
    if (leaf == "cycle") key = "cycle:" + j["event"].get<std::string>();
    if (leaf == "online") key = std::string("online:") + (j["online"] ? "yes" : "no");
    if (!key.empty() && (out.empty() || out.back() != key)) out.push_back(key);
  }
  return out;
}

// The served trajectory's program cycles: the rows with a program line (t, line, … columns).
struct ServedRun {
  double first_t = -1, last_t = -1;
  std::size_t rows = 0;
};

ServedRun served_run(const fs::path& csv) {
  ServedRun r;
  std::istringstream in(read_text(csv));
  std::string row;
  std::getline(in, row);  // header
  while (std::getline(in, row)) {
    const std::size_t c1 = row.find(',');
    const std::size_t c2 = row.find(',', c1 + 1);
    if (std::stoul(row.substr(c1 + 1, c2 - c1 - 1)) == 0) continue;
    const double t = std::stod(row.substr(0, c1));
    if (r.rows++ == 0) r.first_t = t;
    r.last_t = t;
  }
  return r;
}

TEST_F(MqttBroker, AServedProgramsEventsArriveInOrderWithTheServedCycleTime) {
  Broker broker(dir);
  ASSERT_TRUE(broker.running()) << broker.log();
  Subscriber sub(dir, broker.port(), "shop/mill1");
  ASSERT_TRUE(sub.ready());
  // In the M0 pause the console waits 0.3 s (for a state that does not come), then resumes.
  write_text(dir / "console.txt",
             "wait Hold 30\nwait Alarm 0.3\nstart\nwait Idle 30\nwait Alarm 0.3\nquit\n");
  std::vector<std::string> args =
      serve_args("mqtt://127.0.0.1:" + std::to_string(broker.port()) + "/shop/mill1");
  args.insert(args.end(), {"--trajectory", (dir / "served.csv").string()});
  Process serve(args, dir / "serve.txt", (dir / "console.txt").string());
  ASSERT_EQ(serve.wait(60s), 0) << serve.output();
  ASSERT_TRUE(sub.wait_for("\"reason\":\"shutdown\"", 10s)) << read_text(dir / "sub.txt");

  const std::vector<Received> ms = sub.messages();
  EXPECT_EQ(sequence(ms),
            (std::vector<std::string>{"online:yes", "state:READY", "cycle:start", "state:ACTIVE",
                                      "state:FEED_HOLD", "state:ACTIVE", "cycle:end", "state:READY",
                                      "online:no"}))
      << read_text(dir / "sub.txt");
  ASSERT_FALSE(ms.empty());
  EXPECT_EQ(ms.front().topic, "shop/mill1/online");

  // The cycle end's time is the served trajectory's: its program rows, first to last.
  const auto end = std::find_if(ms.begin(), ms.end(), [](const Received& m) {
    return m.topic == "shop/mill1/cycle" && m.payload.find("\"end\"") != std::string::npos;
  });
  ASSERT_NE(end, ms.end());
  const json e = json::parse(end->payload);
  const ServedRun run = served_run(dir / "served.csv");
  ASSERT_GT(run.rows, 100U);
  EXPECT_EQ(e["result"], "completed");
  EXPECT_EQ(e["cycles"].get<std::size_t>(), run.rows);
  EXPECT_NEAR(e["cycle_time_s"].get<double>(), run.last_t - run.first_t, 1e-6);
  EXPECT_GT(e["cycle_time_s"].get<double>(), 0.3);  // the M0 pause is part of the cycle
  EXPECT_EQ(e["program"], (dir / "part.ngc").string());

  // Samples: QoS 0, ten a second, the tool seen at the program's corners.
  std::vector<json> samples;
  for (const Received& m : ms) {
    if (m.topic == "shop/mill1/sample") samples.push_back(json::parse(m.payload));
  }
  ASSERT_GE(samples.size(), 5U);
  bool at_corner = false;
  for (std::size_t i = 0; i < samples.size(); ++i) {
    const json& a = samples[i]["actual_mm"];
    if (std::abs(a["X"].get<double>() - 30) < 0.01 && std::abs(a["Y"].get<double>()) < 0.01) {
      at_corner = true;  // the M0 stop at X30 Y0
    }
    if (i > 0) {
      EXPECT_GT(samples[i]["cycle"], samples[i - 1]["cycle"]);
    }
    EXPECT_EQ(samples[i]["dropped"], 0);
  }
  EXPECT_TRUE(at_corner);
  const json& last = samples.back()["actual_mm"];
  EXPECT_NEAR(last["X"].get<double>(), 30, 0.01);
  EXPECT_NEAR(last["Y"].get<double>(), 20, 0.01);

  // What a dashboard connecting later gets: the retained topics, the controller offline.
  Process late({find_program("mosquitto_sub"), "-h", "127.0.0.1", "-p",
                std::to_string(broker.port()), "-v", "-t", "shop/mill1/#", "-W", "2"},
               dir / "late.txt");
  late.wait(10s);
  const std::string retained = late.output();
  EXPECT_NE(retained.find("shop/mill1/online {\"online\":false"), std::string::npos) << retained;
  EXPECT_NE(retained.find("shop/mill1/state {"), std::string::npos) << retained;
  EXPECT_NE(retained.find("shop/mill1/program {"), std::string::npos) << retained;
  EXPECT_EQ(retained.find("shop/mill1/sample"), std::string::npos) << retained;
  EXPECT_EQ(retained.find("shop/mill1/cycle"), std::string::npos) << retained;
}

TEST_F(MqttBroker, TheLastWillFiresWhenTheControllerIsKilled) {
  Broker broker(dir);
  ASSERT_TRUE(broker.running()) << broker.log();
  Subscriber sub(dir, broker.port(), "shop/mill2");
  ASSERT_TRUE(sub.ready());
  Process serve(serve_args("mqtt://127.0.0.1:" + std::to_string(broker.port()) + "/shop/mill2"),
                dir / "serve.txt");
  ASSERT_TRUE(sub.wait_for("\"online\":true", 10s)) << serve.output();
  ASSERT_TRUE(sub.wait_for("shop/mill2/cycle", 10s)) << serve.output();
  serve.signal(SIGKILL);
  EXPECT_EQ(serve.wait(10s), 128 + SIGKILL);
  EXPECT_TRUE(sub.wait_for("\"reason\":\"connection lost\"", 10s)) << read_text(dir / "sub.txt");
  const std::vector<std::string> seq = sequence(sub.messages());
  ASSERT_FALSE(seq.empty());
  EXPECT_EQ(seq.front(), "online:yes");
  EXPECT_EQ(seq.back(), "online:no");
  EXPECT_EQ(std::count(seq.begin(), seq.end(), "online:no"), 1);
}

// A CA, and a broker certificate for 127.0.0.1 signed by it (openssl, in the test's folder).
void make_test_ca(const fs::path& dir) {
  const std::string openssl = find_program("openssl");
  write_text(dir / "ext.cnf", "subjectAltName=IP:127.0.0.1,DNS:localhost\n");
  const std::vector<std::vector<std::string>> steps = {
      {openssl, "req", "-x509", "-newkey", "rsa:2048", "-nodes", "-days", "2", "-subj",
       "/CN=cncore test CA", "-keyout", (dir / "ca.key").string(), "-out",
       (dir / "ca.crt").string()},
      {openssl, "req", "-newkey", "rsa:2048", "-nodes", "-subj", "/CN=127.0.0.1", "-keyout",
       (dir / "server.key").string(), "-out", (dir / "server.csr").string()},
      {openssl, "x509", "-req", "-days", "2", "-in", (dir / "server.csr").string(), "-CA",
       (dir / "ca.crt").string(), "-CAkey", (dir / "ca.key").string(), "-CAcreateserial",
       "-extfile", (dir / "ext.cnf").string(), "-out", (dir / "server.crt").string()}};
  for (const auto& step : steps) {
    Process p(step, dir / "openssl.txt");
    ASSERT_EQ(p.wait(60s), 0) << p.output();
  }
}

TEST_F(MqttBroker, TlsWithTheTestCaWorksAndAnUnknownCaIsRefusedAtStart) {
  ASSERT_NO_FATAL_FAILURE(make_test_ca(dir));
  Broker broker(dir, {dir / "ca.crt", dir / "server.crt", dir / "server.key", {}});
  ASSERT_TRUE(broker.running()) << broker.log();
  Subscriber sub(dir, broker.port(), "shop/tls", {"--cafile", (dir / "ca.crt").string()});
  ASSERT_TRUE(sub.ready()) << broker.log();
  const std::string url = "mqtts://127.0.0.1:" + std::to_string(broker.port()) + "/shop/tls";
  write_text(dir / "console.txt", "wait Hold 30\nstart\nwait Idle 30\nquit\n");
  std::vector<std::string> args = serve_args(url);
  args.insert(args.end(), {"--mqtt-ca", (dir / "ca.crt").string()});
  Process serve(args, dir / "serve.txt", (dir / "console.txt").string());
  ASSERT_EQ(serve.wait(60s), 0) << serve.output();
  ASSERT_TRUE(sub.wait_for("\"reason\":\"shutdown\"", 10s)) << read_text(dir / "sub.txt");
  const std::vector<std::string> seq = sequence(sub.messages());
  EXPECT_NE(std::find(seq.begin(), seq.end(), "cycle:end"), seq.end())
      << read_text(dir / "sub.txt");

  // Without the CA the broker's certificate is not trusted: a usage error before anything runs.
  Process untrusted(serve_args(url), dir / "untrusted.txt");
  EXPECT_EQ(untrusted.wait(30s), 2) << untrusted.output();
  EXPECT_NE(untrusted.output().find("TLS handshake failed"), std::string::npos)
      << untrusted.output();
}

TEST_F(MqttBroker, AWrongPasswordIsRefusedAtStartAndTheRightOneIsTaken) {
  Process passwd(
      {find_program("mosquitto_passwd"), "-c", "-b", (dir / "passwords").string(), "cnc", "s3cret"},
      dir / "passwd.txt");
  ASSERT_EQ(passwd.wait(30s), 0) << passwd.output();
  Broker broker(dir, {{}, {}, {}, dir / "passwords"});
  ASSERT_TRUE(broker.running()) << broker.log();
  Subscriber sub(dir, broker.port(), "shop/auth", {"-u", "cnc", "-P", "s3cret"});
  ASSERT_TRUE(sub.ready()) << broker.log();
  const std::string url = "mqtt://127.0.0.1:" + std::to_string(broker.port()) + "/shop/auth";

  write_text(dir / "wrong.txt", "guess\n");
  std::vector<std::string> wrong = serve_args(url);
  wrong.insert(wrong.end(),
               {"--mqtt-user", "cnc", "--mqtt-password-file", (dir / "wrong.txt").string()});
  Process refused(wrong, dir / "refused.txt");
  EXPECT_EQ(refused.wait(30s), 2) << refused.output();
  EXPECT_NE(refused.output().find("the broker refused the login of user 'cnc'"), std::string::npos)
      << refused.output();

  write_text(dir / "right.txt", "s3cret\n");
  write_text(dir / "console.txt", "quit\n");
  std::vector<std::string> right = serve_args(url);
  right.insert(right.end(),
               {"--mqtt-user", "cnc", "--mqtt-password-file", (dir / "right.txt").string()});
  Process taken(right, dir / "taken.txt", (dir / "console.txt").string());
  EXPECT_EQ(taken.wait(30s), 0) << taken.output();
  EXPECT_TRUE(sub.wait_for("\"online\":true", 10s)) << read_text(dir / "sub.txt");
}

TEST_F(MqttBroker, ABrokerDownAtStartDoesNotHoldTheMachineAndIsJoinedWhenItComes) {
  const std::uint16_t port = free_port();
  Process serve(serve_args("mqtt://127.0.0.1:" + std::to_string(port) + "/shop/late"),
                dir / "serve.txt");
  ASSERT_TRUE(serve.wait_output("no connection", 15s)) << serve.output();
  // Meanwhile the program runs to its M0 pause; then the broker comes.
  std::this_thread::sleep_for(1s);
  Broker broker(dir, {}, port);
  ASSERT_TRUE(broker.running()) << broker.log();
  Subscriber sub(dir, broker.port(), "shop/late");
  ASSERT_TRUE(sub.ready());
  // The retained state the birth left: the controller reached the pause with no broker.
  Process late({find_program("mosquitto_sub"), "-h", "127.0.0.1", "-p", std::to_string(port), "-v",
                "-t", "shop/late/state", "-C", "1", "-W", "40"},
               dir / "late.txt");
  EXPECT_EQ(late.wait(45s), 0) << serve.output();
  EXPECT_NE(late.output().find("\"execution\":\"FEED_HOLD\""), std::string::npos)
      << late.output() << serve.output();
  ASSERT_TRUE(sub.wait_for("/sample", 10s)) << serve.output();
  // Samples sent while there was no broker are counted as dropped.
  const std::vector<Received> ms = sub.messages();
  const auto sample = std::find_if(ms.begin(), ms.end(),
                                   [](const Received& m) { return m.topic == "shop/late/sample"; });
  ASSERT_NE(sample, ms.end());
  EXPECT_GT(json::parse(sample->payload)["dropped"].get<int>(), 0);
  serve.signal(SIGTERM);
  EXPECT_EQ(serve.wait(30s), 0) << serve.output();
  EXPECT_TRUE(sub.wait_for("\"reason\":\"shutdown\"", 10s)) << read_text(dir / "sub.txt");
}

}  // namespace
