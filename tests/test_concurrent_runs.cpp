// Independent corrections on several threads give exactly the results they give one after the
// other (the contract `driftcorr correct -j N` relies on): no shared mutable state in the
// pipeline, the map readers, geodesy (one PROJ context per projection) or the solver (the calls
// into Ipopt's MUMPS take turns).
#include <gtest/gtest.h>

#include <string>
#include <thread>
#include <vector>

#include "driftcorr/pipeline/pipeline.h"
#include "test_support.h"

namespace driftcorr {
namespace {

std::string Generate(const std::string& name, const std::string& args) {
    static const std::filesystem::path root = test::FreshProcessDir("concurrent");
    const std::string dir = test::EmptySubdir(root, name);
    EXPECT_EQ(test::GenerateRoadScenario(dir, args), 0) << args;
    return dir;
}

void ExpectIdentical(const pipeline::CorrectionRun& a, const pipeline::CorrectionRun& b) {
    EXPECT_EQ(a.result.status, b.result.status);
    EXPECT_EQ(a.result.iterations, b.result.iterations);
    EXPECT_EQ(a.verdict.level, b.verdict.level);
    ASSERT_EQ(a.corrected_frame.size(), b.corrected_frame.size());
    for (std::size_t i = 0; i < a.corrected_frame.size(); ++i) {
        // Bit for bit: the same inputs through the same code must give the same doubles.
        ASSERT_EQ(a.corrected_frame.p_frame[i], b.corrected_frame.p_frame[i]) << "pose " << i;
        ASSERT_EQ(a.corrected_frame.q_frame_body[i].coeffs(),
                  b.corrected_frame.q_frame_body[i].coeffs())
            << "pose " << i;
    }
}

TEST(ConcurrentRuns, ThreadsGiveTheSequentialResults) {
    const std::vector<std::string> scenarios = {
        Generate("a", "--duration-s 90 --seed 1"), Generate("b", "--duration-s 90 --seed 2"),
        Generate("c", "--duration-s 90 --seed 3 --scale-error 1.04")};
    const pipeline::PipelineConfig config;
    std::vector<pipeline::CorrectionRun> sequential;
    for (const std::string& s : scenarios) sequential.push_back(pipeline::RunCorrection(s, config));

    // Every scenario twice, all six at once.
    std::vector<pipeline::CorrectionRun> concurrent(2 * scenarios.size());
    std::vector<std::thread> threads;
    for (std::size_t i = 0; i < concurrent.size(); ++i) {
        threads.emplace_back([&, i] {
            concurrent[i] = pipeline::RunCorrection(scenarios[i % scenarios.size()], config);
        });
    }
    for (std::thread& t : threads) t.join();
    for (std::size_t i = 0; i < concurrent.size(); ++i) {
        SCOPED_TRACE("run " + std::to_string(i));
        ASSERT_TRUE(Usable(sequential[i % scenarios.size()].result.status));
        ExpectIdentical(sequential[i % scenarios.size()], concurrent[i]);
    }
}

}  // namespace
}  // namespace driftcorr
