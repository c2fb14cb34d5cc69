// End-to-end tests of where the `driftcorr` CLI writes: no output may destroy an input (however
// the path is spelled), a symbolic link is followed and a device or FIFO written in place (never
// replaced), standard output is an output like any other (-o -, a full disk behind it is an
// error), timestamps in another unit are refused naming the file and line, and SIGTERM ends a
// stream with its summary. One synthetic scenario (a 60 s drive) is generated per test process.
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

#include "test_support.h"

namespace {

namespace fs = std::filesystem;

const std::string kCli = DRIFTCORR_BINARY_DIR "/examples/driftcorr";
constexpr int kExitOk = 0, kExitBadInput = 2;

using driftcorr::test::ReadFile;
using driftcorr::test::WriteFile;

std::string Quote(const std::string& s) {
    std::string out = "'";
    for (char c : s) out += c == '\'' ? std::string("'\\''") : std::string(1, c);
    return out + "'";
}

struct Shell {
    int exit_code = -1;
    std::string out, err;
};

/// Runs `command` through sh with stdout and stderr captured (unless the command redirects them
/// itself), within 120 s.
Shell RunShell(const std::string& command, const fs::path& dir) {
    const fs::path out = dir / "stdout.txt", err = dir / "stderr.txt";
    const std::string shell = "timeout 120 sh -c " + Quote(command) + " >" + Quote(out.string()) +
                              " 2>" + Quote(err.string()) + " </dev/null";
    const int status = std::system(shell.c_str());
    Shell r;
    if (status != -1 && WIFEXITED(status)) r.exit_code = WEXITSTATUS(status);
    r.out = ReadFile(out);
    r.err = ReadFile(err);
    return r;
}

std::string Join(const std::vector<std::string>& args) {
    std::string out;
    for (const std::string& a : args) out += (out.empty() ? "" : " ") + Quote(a);
    return out;
}

/// Data lines of a TUM text.
std::size_t PoseLines(const std::string& text) {
    std::istringstream in(text);
    std::size_t n = 0;
    for (std::string line; std::getline(in, line);) {
        if (!line.empty() && line[0] != '#') ++n;
    }
    return n;
}

class CliOutputs : public ::testing::Test {
protected:
    static void SetUpTestSuite() {
        root_ = driftcorr::test::FreshProcessDir("test_cli_outputs");
        base_ = root_ / "valid_scenario";
        generated_ =
            driftcorr::test::GenerateRoadScenario(base_.string(), "--duration-s 60") == 0 &&
            fs::exists(base_ / "scenario.yaml");
    }
    static void TearDownTestSuite() {
        const auto* suite = ::testing::UnitTest::GetInstance()->current_test_suite();
        if (suite == nullptr || suite->Passed()) fs::remove_all(root_);
    }
    void SetUp() override {
        ASSERT_TRUE(generated_) << "generating the scenario failed";
        const std::string name = ::testing::UnitTest::GetInstance()->current_test_info()->name();
        dir_ = root_ / name;
        fs::remove_all(dir_);
        scenario_ = dir_ / "scenario";
        fs::create_directories(dir_ / "out");
        fs::copy(base_, scenario_, fs::copy_options::recursive);
        estimate_before_ = ReadFile(scenario_ / "estimate.tum");
        map_before_ = ReadFile(scenario_ / "map.osm");
    }
    /// `driftcorr correct <scenario> args...`
    Shell Correct(const std::vector<std::string>& args, const std::string& redirect = "") {
        std::vector<std::string> all = {kCli, "correct", scenario_.string(), "-q"};
        all.insert(all.end(), args.begin(), args.end());
        return RunShell(Join(all) + redirect, dir_);
    }
    /// The inputs are as they were, byte for byte.
    void ExpectInputsIntact() const {
        EXPECT_EQ(ReadFile(scenario_ / "estimate.tum"), estimate_before_);
        EXPECT_EQ(ReadFile(scenario_ / "map.osm"), map_before_);
    }

    static inline fs::path root_, base_;
    static inline bool generated_ = false;
    fs::path dir_, scenario_;
    std::string estimate_before_, map_before_;
};

TEST_F(CliOutputs, OutputNamingTheEstimateIsRefusedBeforeAnyWork) {
    const Shell r = Correct({"-o", (scenario_ / "estimate.tum").string()});
    EXPECT_EQ(r.exit_code, kExitBadInput) << r.err;
    EXPECT_NE(r.err.find("-o: is the estimate"), std::string::npos) << r.err;
    ExpectInputsIntact();
}

TEST_F(CliOutputs, OutputNamingTheEstimateThroughDotDotOrALinkIsRefused) {
    fs::create_directories(scenario_ / "sub");
    Shell r = Correct({"-o", (scenario_ / "sub" / ".." / "estimate.tum").string()});
    EXPECT_EQ(r.exit_code, kExitBadInput) << r.err;
    EXPECT_NE(r.err.find("is the estimate"), std::string::npos) << r.err;
    fs::create_symlink(scenario_ / "estimate.tum", dir_ / "out" / "link.tum");
    r = Correct({"-o", (dir_ / "out" / "link.tum").string()});
    EXPECT_EQ(r.exit_code, kExitBadInput) << r.err;
    EXPECT_NE(r.err.find("is the estimate"), std::string::npos) << r.err;
    fs::create_hard_link(scenario_ / "estimate.tum", dir_ / "out" / "hard.tum");
    r = Correct({"-o", (dir_ / "out" / "hard.tum").string()});
    EXPECT_EQ(r.exit_code, kExitBadInput) << r.err;
    ExpectInputsIntact();
}

TEST_F(CliOutputs, OutputNamingTheMapTheScenarioOrTheConfigIsRefused) {
    WriteFile(dir_ / "params.yaml", "model:\n  map_weight: 0.8\n");
    const std::string params_before = ReadFile(dir_ / "params.yaml");
    const std::string yaml_before = ReadFile(scenario_ / "scenario.yaml");
    const std::vector<std::pair<std::string, std::string>> cases = {
        {"-o", (scenario_ / "map.osm").string()},
        {"--geojson", (scenario_ / "scenario.yaml").string()},
        {"--covariance", (dir_ / "params.yaml").string()},
    };
    for (const auto& [option, path] : cases) {
        std::vector<std::string> args = {"--config", (dir_ / "params.yaml").string(), "-o",
                                         (dir_ / "out" / "c.tum").string()};
        if (option == "-o") {
            args[3] = path;
        } else {
            args.insert(args.end(), {option, path});
        }
        const Shell r = Correct(args);
        EXPECT_EQ(r.exit_code, kExitBadInput) << option << " " << path << ": " << r.err;
        EXPECT_NE(r.err.find(option + ": is "), std::string::npos) << r.err;
    }
    ExpectInputsIntact();
    EXPECT_EQ(ReadFile(scenario_ / "scenario.yaml"), yaml_before);
    EXPECT_EQ(ReadFile(dir_ / "params.yaml"), params_before);
    EXPECT_FALSE(fs::exists(dir_ / "out" / "c.tum"));
}

TEST_F(CliOutputs, TwoOutputsOnOneFileAreRefused) {
    const std::string out = (dir_ / "out" / "c.tum").string();
    const Shell r = Correct({"-o", out, "--covariance", out});
    EXPECT_EQ(r.exit_code, kExitBadInput) << r.err;
    EXPECT_NE(r.err.find("same file as -o"), std::string::npos) << r.err;
    EXPECT_FALSE(fs::exists(out));
}

TEST_F(CliOutputs, NoScenarioOfABatchWritesAnotherOnesInput) {
    // Scenario "second" reads its estimate from out/scenario.tum, the file the batch's first
    // scenario ("scenario") would write: the whole batch is refused before any work, in either
    // order, and that estimate is left as it was.
    const fs::path second = dir_ / "second";
    fs::copy(scenario_, second, fs::copy_options::recursive);
    fs::copy_file(second / "estimate.tum", dir_ / "out" / "scenario.tum");
    fs::remove(second / "estimate.tum");
    std::string yaml = ReadFile(second / "scenario.yaml");
    yaml = std::regex_replace(yaml, std::regex(R"(path:\s*estimate\.tum)"),
                              "path: ../out/scenario.tum");
    WriteFile(second / "scenario.yaml", yaml);
    for (const bool second_first : {false, true}) {
        const std::string a = second_first ? second.string() : scenario_.string();
        const std::string b = second_first ? scenario_.string() : second.string();
        const Shell r = RunShell(
            Join({kCli, "correct", a, b, "-q", "-o", (dir_ / "out").string() + "/"}), dir_);
        EXPECT_EQ(r.exit_code, kExitBadInput) << r.err;
        EXPECT_NE(r.err.find("-o: is the estimate of argument " +
                             std::string(second_first ? "1" : "2") + " (second)"),
                  std::string::npos)
            << r.err;
        EXPECT_EQ(ReadFile(dir_ / "out" / "scenario.tum"), estimate_before_);
        EXPECT_FALSE(fs::exists(dir_ / "out" / "second.tum"));
    }
    ExpectInputsIntact();
}

TEST_F(CliOutputs, TrajectoryFileWithOsmRefusesToOverwriteItself) {
    const std::string yaml = ReadFile(scenario_ / "scenario.yaml");
    std::smatch lat, lon, yaw;
    ASSERT_TRUE(std::regex_search(yaml, lat, std::regex(R"(lat_deg:\s*([-0-9.eE+]+))")));
    ASSERT_TRUE(std::regex_search(yaml, lon, std::regex(R"(lon_deg:\s*([-0-9.eE+]+))")));
    ASSERT_TRUE(std::regex_search(yaml, yaw, std::regex(R"(yaw_deg:\s*([-0-9.eE+]+))")));
    const std::string traj = (scenario_ / "estimate.tum").string();
    const std::string anchor = lat[1].str() + "," + lon[1].str() + "," + yaw[1].str();
    for (const std::string& out : {traj, (scenario_ / "map.osm").string()}) {
        const Shell r =
            RunShell(Join({kCli, "correct", traj, "--osm", (scenario_ / "map.osm").string(),
                           "--anchor", anchor, "--frame", "enu", "-q", "-o", out}),
                     dir_);
        EXPECT_EQ(r.exit_code, kExitBadInput) << r.err;
        EXPECT_NE(r.err.find("-o: is "), std::string::npos) << r.err;
    }
    ExpectInputsIntact();
}

TEST_F(CliOutputs, ASymbolicLinkIsFollowedAndKept) {
    const fs::path target = dir_ / "out" / "target.tum", link = dir_ / "out" / "link.tum";
    WriteFile(target, "old\n");
    fs::create_symlink(target, link);
    const Shell r = Correct({"-o", link.string()});
    ASSERT_EQ(r.exit_code, kExitOk) << r.err;
    EXPECT_TRUE(fs::is_symlink(link));
    EXPECT_EQ(PoseLines(ReadFile(target)), PoseLines(estimate_before_));
    for (const auto& e : fs::directory_iterator(dir_ / "out")) {
        EXPECT_EQ(e.path().filename().string().find(".tmp."), std::string::npos) << e.path();
    }
}

TEST_F(CliOutputs, DeviceAndFifoAreWrittenInPlaceNotReplaced) {
    Shell r = Correct({"-o", "/dev/null"});
    ASSERT_EQ(r.exit_code, kExitOk) << r.err;
    struct stat st {};
    ASSERT_EQ(::stat("/dev/null", &st), 0);
    EXPECT_TRUE(S_ISCHR(st.st_mode)) << "/dev/null is no longer a character device";

    const fs::path fifo = dir_ / "out" / "fifo", copy = dir_ / "copy.tum";
    ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
    r = RunShell("cat " + Quote(fifo.string()) + " > " + Quote(copy.string()) + " & " +
                     Join({kCli, "correct", scenario_.string(), "-q", "-o", fifo.string()}) +
                     "; code=$?; wait; exit $code",
                 dir_);
    ASSERT_EQ(r.exit_code, kExitOk) << r.err;
    ASSERT_EQ(::stat(fifo.c_str(), &st), 0);
    EXPECT_TRUE(S_ISFIFO(st.st_mode)) << "the FIFO was replaced";
    EXPECT_EQ(PoseLines(ReadFile(copy)), PoseLines(estimate_before_));
}

TEST_F(CliOutputs, DashWritesTheTrajectoryToStandardOutputAndTheSummaryToStderr) {
    const Shell r = Correct({"-o", "-"});
    ASSERT_EQ(r.exit_code, kExitOk) << r.err;
    EXPECT_EQ(PoseLines(r.out), PoseLines(estimate_before_)) << r.out.substr(0, 300);
    EXPECT_NE(r.err.find("verdict"), std::string::npos) << r.err;
    EXPECT_FALSE(fs::exists(dir_ / "-"));
}

TEST_F(CliOutputs, OneScenarioAndAFolderOutputWritesIntoTheFolder) {
    const Shell r = Correct({"-o", (dir_ / "out").string() + "/"});
    ASSERT_EQ(r.exit_code, kExitOk) << r.err << r.out;
    EXPECT_TRUE(fs::exists(dir_ / "out" / "scenario.tum")) << r.out;
}

TEST_F(CliOutputs, AFullStandardOutputIsAnErrorNotASuccess) {
    const Shell r = Correct({"-o", (dir_ / "out" / "c.tum").string()}, " > /dev/full");
    EXPECT_EQ(r.exit_code, kExitBadInput) << r.err;
    EXPECT_NE(r.err.find("standard output: write failed"), std::string::npos) << r.err;

    const Shell s = RunShell(Join({kCli, "stream", scenario_.string(), "-q"}) + " < " +
                                 Quote((scenario_ / "estimate.tum").string()) + " > /dev/full",
                             dir_);
    EXPECT_EQ(s.exit_code, kExitBadInput) << s.err;
    EXPECT_NE(s.err.find("standard output: write failed"), std::string::npos) << s.err;
    EXPECT_EQ(s.err.find("poses corrected"), std::string::npos) << s.err;
}

TEST_F(CliOutputs, AFileSizeLimitIsReportedWithItsReason) {
    const fs::path out = dir_ / "out" / "c.tum";
    const Shell r = Correct({"-o", out.string()}, "");
    ASSERT_EQ(r.exit_code, kExitOk) << r.err;
    const Shell limited =
        RunShell("ulimit -f 8; exec " + Join({kCli, "correct", scenario_.string(), "-q", "-o",
                                              (dir_ / "out" / "d.tum").string()}),
                 dir_);
    EXPECT_EQ(limited.exit_code, kExitBadInput) << limited.err;
    EXPECT_NE(limited.err.find("File too large"), std::string::npos) << limited.err;
    EXPECT_FALSE(fs::exists(dir_ / "out" / "d.tum"));
}

TEST_F(CliOutputs, NanosecondTimestampsAreRefusedNamingFileAndLine) {
    // The estimate's timestamps in nanoseconds since the epoch, as a ROS export writes them.
    std::istringstream in(estimate_before_);
    std::string text;
    for (std::string line; std::getline(in, line);) {
        if (line.empty() || line[0] == '#') continue;
        const std::size_t space = line.find(' ');
        const double t = std::stod(line.substr(0, space));
        char stamp[40];
        std::snprintf(stamp, sizeof(stamp), "%.0f", 1.6e18 + t * 1e9);
        text += stamp + line.substr(space) + "\n";
    }
    WriteFile(scenario_ / "estimate.tum", text);
    const Shell r = Correct({"-o", (dir_ / "out" / "c.tum").string()});
    EXPECT_EQ(r.exit_code, kExitBadInput) << r.err;
    EXPECT_NE(r.err.find("estimate.tum:1: timestamp"), std::string::npos) << r.err;
    EXPECT_NE(r.err.find("nanoseconds"), std::string::npos) << r.err;

    const Shell s = RunShell(Join({kCli, "stream", scenario_.string(), "-q"}) + " < " +
                                 Quote((scenario_ / "estimate.tum").string()),
                             dir_);
    EXPECT_EQ(s.exit_code, kExitBadInput) << s.err;
    EXPECT_NE(s.err.find("standard input:1: timestamp"), std::string::npos) << s.err;
    EXPECT_EQ(PoseLines(s.out), 0u);
}

TEST_F(CliOutputs, SigtermEndsTheStreamWithItsSummaryAndExit143) {
    // The poses, then an input that stays open (blank lines, which the stream skips, until the
    // stream has gone and the pipe breaks): the stream waits for more until SIGTERM, sent once
    // every pose's line is out (at most 300 s: a slow build takes seconds for them).
    const std::string out = (dir_ / "sigterm_out.tum").string();
    const std::string command =
        ": > " + Quote(out) + "; (cat " + Quote((scenario_ / "estimate.tum").string()) +
        "; while sleep 0.2; do echo || exit 0; done) | " +
        Join({kCli, "stream", scenario_.string(), "--sync"}) + " > " + Quote(out) +
        " & pid=$!; n=0; while [ $(grep -c . " + Quote(out) + ") -lt " +
        std::to_string(PoseLines(estimate_before_)) +
        " ] && [ $n -lt 1500 ]; do sleep 0.2; n=$((n + 1)); done; sleep 0.5; kill -TERM $pid; "
        "wait $pid; s=$?; cat " +
        Quote(out) + "; exit $s";
    const Shell r = RunShell(command, dir_);
    EXPECT_EQ(r.exit_code, 143) << r.err;
    EXPECT_NE(r.err.find("SIGTERM"), std::string::npos) << r.err;
    EXPECT_NE(r.err.find("poses corrected"), std::string::npos) << r.err;
    EXPECT_EQ(PoseLines(r.out), PoseLines(estimate_before_));
    std::istringstream lines(r.out);
    for (std::string line; std::getline(lines, line);) {
        std::istringstream fields(line);
        const std::vector<std::string> f{std::istream_iterator<std::string>(fields), {}};
        ASSERT_EQ(f.size(), 8u) << "an incomplete line: " << line;
    }
}

TEST_F(CliOutputs, UnboundedOrMalformedInputsAreRefusedNamingTheFile) {
    const std::string out = (dir_ / "out" / "c.tum").string();
    struct Case {
        std::string config;    ///< --config, or "" for none
        std::string expected;  ///< in the message
    };
    fs::create_directories(dir_ / "config_folder");
    WriteFile(dir_ / "nested.yaml", "model: " + std::string(100000, '[') + "\n");
    WriteFile(dir_ / "two.yaml", "model: {map_weight: 0.8}\n---\nmodel: {map_weight: 0.1}\n");
    WriteFile(dir_ / "big.yaml", "# " + std::string(5u << 20, 'x') + "\n");
    const std::vector<Case> cases = {
        {(dir_ / "config_folder").string(), "config_folder: is a folder, not a file"},
        {(dir_ / "nested.yaml").string(), "nested too deeply"},
        {(dir_ / "two.yaml").string(), "two.yaml:2: a second YAML document"},
        {(dir_ / "big.yaml").string(), "big.yaml:1: line longer than 1 MiB"},
    };
    for (const Case& c : cases) {
        const Shell r = Correct({"-o", out, "--config", c.config});
        EXPECT_EQ(r.exit_code, kExitBadInput) << r.err;
        EXPECT_NE(r.err.find(c.expected), std::string::npos) << r.err;
        EXPECT_EQ(r.err.find("internal error"), std::string::npos) << r.err;
    }
    // An estimate that never ends is refused at its first 64 KiB line, not read into memory.
    fs::remove(scenario_ / "estimate.tum");
    fs::create_symlink("/dev/zero", scenario_ / "estimate.tum");
    const Shell r = Correct({"-o", out});
    EXPECT_EQ(r.exit_code, kExitBadInput) << r.err;
    EXPECT_NE(r.err.find("estimate.tum:1: line longer than 64 KiB"), std::string::npos) << r.err;
    EXPECT_FALSE(fs::exists(out));
}

TEST_F(CliOutputs, AWayWithAMissingNodeIsSplitAndSaidSo) {
    // The first way of the generated map gets a reference to a node the file does not hold.
    std::string map = ReadFile(scenario_ / "map.osm");
    const std::size_t at = map.find("<nd ref=");
    ASSERT_NE(at, std::string::npos);
    map.insert(at, "<nd ref=\"987654321\"/>\n    ");
    WriteFile(scenario_ / "map.osm", map);
    const Shell r = Correct({"-o", (dir_ / "out" / "c.tum").string()});
    EXPECT_EQ(r.exit_code, kExitOk) << r.err;
    EXPECT_NE(r.err.find("warning: map: 1 node reference(s) of highway ways have no <node>"),
              std::string::npos)
        << r.err;
}

TEST_F(CliOutputs, VerdictThresholdsAreParameters) {
    // The generated drive accelerates and brakes gently: a platform held to 0.01 m/s^2 makes
    // every change of speed an input jump, and the same correction degraded; a misspelt key is
    // refused by name.
    WriteFile(dir_ / "narrow.yaml", "verdict: {max_accel_mps2: 0.01}\n");
    const Shell r = Correct(
        {"-o", (dir_ / "out" / "c.tum").string(), "--config", (dir_ / "narrow.yaml").string()});
    EXPECT_EQ(r.exit_code, kExitOk) << r.err;
    EXPECT_NE(r.out.find("verdict    degraded"), std::string::npos) << r.out;
    WriteFile(dir_ / "typo.yaml", "verdict: {scale_plausible_mni: 0.9}\n");
    const Shell t = Correct(
        {"-o", (dir_ / "out" / "d.tum").string(), "--config", (dir_ / "typo.yaml").string()});
    EXPECT_EQ(t.exit_code, kExitBadInput) << t.err;
    EXPECT_NE(t.err.find("verdict.scale_plausible_mni"), std::string::npos) << t.err;
}

TEST(CliVersion, PrintsTheVersion) {
    const fs::path dir = driftcorr::test::FreshProcessDir("test_cli_version");
    const Shell r = RunShell(Quote(kCli) + " --version", dir);
    EXPECT_EQ(r.exit_code, kExitOk);
    EXPECT_TRUE(std::regex_search(r.out, std::regex(R"(^driftcorr [0-9]+\.[0-9]+\.[0-9]+\n$)")))
        << r.out;
}

}  // namespace
