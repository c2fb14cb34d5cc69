#pragma once
// The scenario folders a benchmark tool runs on: its arguments, or the 7 KITTI scenarios of
// ../shared/datasets. Folders that do not exist are reported and skipped.
#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

namespace driftcorr::bench {

template <typename Fn>
int ForEachScenario(int argc, char** argv, Fn&& evaluate) {
    std::vector<std::string> dirs(argv + 1, argv + argc);
    if (dirs.empty()) {
        for (const char* s :
             {"kitti00_cvo_stereo_geometric", "kitti05_cvo_stereo_geometric",
              "kitti07_cvo_stereo_geometric", "kitti00_gicp_frame2frame",
              "kitti05_gicp_frame2frame", "kitti07_gicp_frame2frame", "kitti00_orb2_longruidong"}) {
            dirs.push_back(std::string(DRIFTCORR_SHARED_DATASETS) + "/" + s);
        }
    }
    for (const std::string& d : dirs) {
        if (!std::filesystem::exists(d)) {
            std::printf("%s: not found, skipped\n", d.c_str());
            continue;
        }
        evaluate(d);
    }
    return 0;
}

}  // namespace driftcorr::bench
