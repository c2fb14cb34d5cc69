// The fuzz seed corpora (tests/fuzz/corpus/<target>/) as a regression suite in the ordinary build:
// every file goes through the same harness as under libFuzzer (tests/fuzz/fuzz_targets.h) and must
// either parse, keeping the parser's documented promises, or throw InputError. Inputs named
// regression-* once crashed a parser; they stay here so the fix stays in.
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iterator>
#include <ostream>
#include <string>
#include <vector>

#include "fuzz/fuzz_targets.h"

namespace {

namespace fs = std::filesystem;

using Harness = std::function<void(std::string_view, const std::string&)>;

struct Target {
    const char* name;  ///< the corpus folder and fuzz_<name> binary
    Harness run;
};

const std::vector<Target>& Targets() {
    static const std::vector<Target> targets = {
        {"tum", driftcorr::fuzz::RunTum},
        {"kitti", driftcorr::fuzz::RunKitti},
        {"scenario_yaml", driftcorr::fuzz::RunScenarioYaml},
        {"osm", driftcorr::fuzz::RunOsm},
        {"params_yaml", driftcorr::fuzz::RunParamsYaml},
        {"geojson", driftcorr::fuzz::RunGeoJson},
        {"pcd", driftcorr::fuzz::RunPcd},
        {"ply", driftcorr::fuzz::RunPly},
        {"octomap", driftcorr::fuzz::RunOctomap},
        {"octomap_ot", driftcorr::fuzz::RunOctomapOt},
    };
    return targets;
}

/// gtest prints the parameter in test names and failures: the target name, not raw bytes.
void PrintTo(const Target& target, std::ostream* os) { *os << target.name; }

std::vector<fs::path> CorpusFiles(const std::string& target) {
    std::vector<fs::path> files;
    for (const auto& entry : fs::directory_iterator(fs::path(DRIFTCORR_FUZZ_CORPUS) / target)) {
        if (entry.is_regular_file()) files.push_back(entry.path());
    }
    std::sort(files.begin(), files.end());
    return files;
}

std::string ReadBytes(const fs::path& path) {
    std::ifstream in(path, std::ios::binary);
    return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

class FuzzCorpus : public ::testing::TestWithParam<Target> {
protected:
    void SetUp() override {
        tmp_dir_ =
            fs::path(DRIFTCORR_TEST_TMPDIR) / ("fuzz_regressions_" + std::to_string(::getpid()));
        fs::create_directories(tmp_dir_);
    }
    void TearDown() override { fs::remove_all(tmp_dir_); }
    fs::path tmp_dir_;
};

TEST_P(FuzzCorpus, EveryFileParsesOrThrowsInputError) {
    const Target& target = GetParam();
    const std::vector<fs::path> files = CorpusFiles(target.name);
    ASSERT_FALSE(files.empty()) << "no seed corpus for " << target.name;
    for (const fs::path& file : files) {
        SCOPED_TRACE(file.string());
        const std::string bytes = ReadBytes(file);
        // FuzzInvariantError (a broken promise) and any other exception fail the test here.
        EXPECT_NO_THROW(target.run(bytes, tmp_dir_.string()));
    }
}

INSTANTIATE_TEST_SUITE_P(AllParsers, FuzzCorpus, ::testing::ValuesIn(Targets()),
                         [](const ::testing::TestParamInfo<Target>& param_info) {
                             return std::string(param_info.param.name);
                         });

/// The valid seeds must really parse (otherwise the corpus would only exercise error paths).
TEST(FuzzCorpusSeeds, ValidSeedsParse) {
    const fs::path corpus(DRIFTCORR_FUZZ_CORPUS);
    const fs::path tmp =
        fs::path(DRIFTCORR_TEST_TMPDIR) / ("fuzz_seeds_" + std::to_string(::getpid()));
    fs::create_directories(tmp);
    const auto write = [&](const fs::path& src, const std::string& name) {
        const fs::path dst = tmp / name;
        fs::copy_file(src, dst, fs::copy_options::overwrite_existing);
        return dst.string();
    };
    EXPECT_EQ(driftcorr::io::ReadTum((corpus / "tum/valid.txt").string()).size(), 4u);
    EXPECT_EQ(driftcorr::io::ReadTum((corpus / "tum/crlf_tabs_no_newline.txt").string()).size(),
              3u);
    EXPECT_EQ(
        driftcorr::io::ReadKitti((corpus / "kitti/valid_rate.txt").string(), std::nullopt, 10.0)
            .size(),
        3u);
    EXPECT_NO_THROW(
        driftcorr::io::LoadScenario(write(corpus / "scenario_yaml/road_kitti.yaml", "a.yaml")));
    EXPECT_NO_THROW(
        driftcorr::io::LoadScenario(write(corpus / "scenario_yaml/indoor_grid.yaml", "b.yaml")));
    const driftcorr::OsmRoads roads = driftcorr::ReadOsmRoads((corpus / "osm/valid.osm").string());
    EXPECT_EQ(roads.ways.size(), 1u);  // way 11 has one resolvable node, way 12 is no highway
    EXPECT_EQ(driftcorr::ReadOsmRoads((corpus / "osm/extract.pbf").string()).ways.size(), 2u);
    EXPECT_NO_THROW(
        driftcorr::pipeline::LoadPipelineConfig((corpus / "params_yaml/full.yaml").string()));
    EXPECT_NO_THROW(
        driftcorr::pipeline::LoadPipelineConfig((corpus / "params_yaml/empty.yaml").string()));
    EXPECT_NO_THROW(driftcorr::pipeline::LoadPipelineConfig(
        (corpus / "params_yaml/indoor_paper.yaml").string()));
    const driftcorr::GeoJsonLayer layer =
        driftcorr::ReadGeoJson((corpus / "geojson/walkways.geojson").string());
    EXPECT_EQ(layer.polygons.size(), 2u);  // the corridor and the wall; the null geometry skipped
    EXPECT_EQ(layer.lines.size(), 1u);
    EXPECT_EQ(driftcorr::ReadSurfacePoints((corpus / "pcd/floor.pcd").string()).size(), 4u);
    EXPECT_EQ(driftcorr::ReadSurfacePoints((corpus / "ply/floor.ply").string()).size(), 4u);
    // 24 voxels in one layer plus one stacked below: 24 floor voxels.
    EXPECT_EQ(driftcorr::ReadSurfacePoints((corpus / "octomap/floor.bt").string()).size(), 24u);
    EXPECT_EQ(driftcorr::ReadSurfacePoints((corpus / "octomap_ot/floor.ot").string()).size(), 12u);
    fs::remove_all(tmp);
}

/// Regressions whose old outcome was a silent wrong result rather than a crash, so the harness
/// alone would not notice them coming back.
TEST(FuzzCorpusSeeds, RegressionsWithSilentWrongResults) {
    const fs::path corpus(DRIFTCORR_FUZZ_CORPUS);
    // 1e200 entries made det and |R^T R - I| NaN, which passed the "> 0.1" checks: identity.
    EXPECT_THROW(driftcorr::io::ReadKitti((corpus / "kitti/regression-nan-rotation.txt").string(),
                                          std::nullopt, 10.0),
                 driftcorr::InputError);
    // Components near 1e200 overflowed q.norm() to inf and normalised q to zero.
    const driftcorr::Trajectory tum =
        driftcorr::io::ReadTum((corpus / "tum/regression-quaternion-overflow.txt").string());
    ASSERT_EQ(tum.size(), 3u);
    EXPECT_NEAR(tum.q_frame_body[1].x(), std::sqrt(0.5), 1e-12);
    EXPECT_NEAR(tum.q_frame_body[1].y(), std::sqrt(0.5), 1e-12);
    // Positions-only TUM lines (t x y z): three poses and no orientations at all (the harness's
    // length invariant predated the format and called it a broken promise).
    const driftcorr::Trajectory positions =
        driftcorr::io::ReadTum((corpus / "tum/regression-positions-only.txt").string());
    EXPECT_EQ(positions.size(), 3u);
    EXPECT_FALSE(positions.HasOrientation());
    // A subnormal rate_hz made every timestamp after the first inf.
    EXPECT_THROW(
        driftcorr::io::ReadKitti((corpus / "kitti/valid_rate.txt").string(), std::nullopt, 1e-320),
        driftcorr::InputError);
}

}  // namespace
