// The compiled part of the `driftcorr` Python package: the pipeline library (examples/pipeline)
// behind numpy arrays. No algorithm here: scenario loading, correction, verdict, covariance,
// metrics and the online corrector are the C++ library's; this file converts and forwards.
//
// Errors: bad arguments raise ValueError / TypeError naming the argument (convert.h); bad files
// (scenario.yaml, trajectories, maps, params.yaml) raise driftcorr.InputError (a ValueError)
// with the library's message naming file, line and key. Solver outcomes are never exceptions:
// they are the result's status and verdict.
//
// Threads: every call that solves releases the GIL; the solver's calls into Ipopt (a final solve
// with an active corridor constraint) take turns (a process-wide lock in optim/ipopt_solver.cpp:
// Debian 12's Ipopt 3.11 with MUMPS is not thread-safe), so to correct several drives at once
// use several processes (the Dask recipe, python/examples/dask_correct.py).
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <chrono>
#include <memory>
#include <mutex>
#include <string>
#include <utility>

#include "convert.h"
#include "driftcorr/core/angles.h"
#include "driftcorr/core/errors.h"
#include "driftcorr/io/trajectory_io.h"
#include "driftcorr/pipeline/online.h"

namespace driftcorr::python {
namespace {

py::list Strings(const std::vector<std::string>& items) {
    py::list out;
    for (const std::string& s : items) out.append(s);
    return out;
}

py::array_t<std::uint8_t> Flags(const std::vector<std::uint8_t>& flags) {
    py::array_t<std::uint8_t> out(py::ssize_t(flags.size()));
    auto w = out.mutable_unchecked<1>();
    for (std::size_t i = 0; i < flags.size(); ++i) w(py::ssize_t(i)) = flags[i];
    return out;
}

py::object OptionalMetrics(const std::optional<ErrorMetrics>& m) {
    return m ? py::object(MetricsToDict(*m)) : py::object(py::none());
}

// The covariance rows when the correction computed them, else None (status and message say why).
void AddCovariance(const CorrectionResult& r, py::dict& d) {
    const CovarianceResult& c = r.covariance;
    d["covariance_status"] = ToString(c.status);
    d["covariance_message"] = c.message;
    d["covariance"] = c.status == CovarianceStatus::kOk
                          ? py::object(CovarianceToArray(r.corrected.t_s, c.poses))
                          : py::object(py::none());
}

py::dict RunToDict(const pipeline::CorrectionRun& run) {
    const CorrectionResult& r = run.result;
    const bool usable = Usable(r.status);
    py::dict d;
    d["name"] = run.scenario.name;
    d["mode"] = io::ToString(run.scenario.mode);
    d["frame"] = ToString(run.scenario.frame);
    d["status"] = ToString(r.status);
    d["message"] = r.message;
    d["usable"] = usable;
    d["corrected"] =
        usable ? py::object(TrajectoryToArray(run.corrected_frame)) : py::object(py::none());
    d["corrected_en"] = usable ? py::object(PlanarToArray(r.corrected)) : py::object(py::none());
    d["estimate_en"] = PlanarToArray(run.estimate);
    d["ground_truth_en"] =
        run.ground_truth ? py::object(PlanarToArray(*run.ground_truth)) : py::object(py::none());
    AddCovariance(r, d);
    d["flags"] = Flags(run.verdict.pose_flags);
    d["verdict"] = ToString(run.verdict.level);
    d["reasons"] = Strings(run.verdict.reasons);
    d["scale_min"] = run.verdict.scale_min;
    d["scale_max"] = run.verdict.scale_max;
    d["input_jumps"] = run.verdict.input_jumps;
    d["off_map_share"] = run.verdict.off_map_share;
    d["metrics_before"] = OptionalMetrics(run.before);
    d["metrics_after"] = OptionalMetrics(run.after);
    std::vector<std::string> warnings = run.scenario.warnings;
    warnings.insert(warnings.end(), r.warnings.begin(), r.warnings.end());
    d["warnings"] = Strings(warnings);
    d["anchor_yaw_deg"] = RadToDeg(run.anchor.yaw_rad);
    d["anchor_origin_en"] = py::make_tuple(run.anchor.origin_en.x(), run.anchor.origin_en.y());
    d["global_scale"] = run.global_scale;
    const pipeline::DriveScale drive = pipeline::DriveScaleOf(run);
    d["drive_scale"] = drive.value;
    d["drive_scale_sd"] = drive.sd;
    py::dict t;
    t["load_s"] = run.timings.load_s;
    t["map_s"] = run.timings.map_s;
    t["solve_s"] = run.timings.solve_s;
    d["timings"] = t;
    d["windows"] = r.windows;
    d["iterations"] = r.iterations;
    return d;
}

pipeline::CorrectionRun Solve(pipeline::PreparedScenario prepared,
                              const pipeline::PipelineConfig& cfg) {
    return pipeline::RunCorrection(std::move(prepared), cfg);
}

py::dict CorrectScenario(const py::object& path, const py::object& config,
                         const std::string& solver) {
    const std::string scenario = PathOf(path, "path");
    const pipeline::PipelineConfig cfg = ConfigFrom(config, solver);
    pipeline::CorrectionRun run;
    {
        py::gil_scoped_release release;
        run = Solve(pipeline::PrepareScenario(scenario, cfg), cfg);
    }
    return RunToDict(run);
}

py::dict CorrectParts(const py::object& trajectory, const py::object& map, const py::object& anchor,
                      const py::object& frame, const py::object& mode,
                      const py::object& ground_truth, const py::object& config,
                      const std::string& solver, const std::string& name) {
    io::Scenario sc = ScenarioFromParts(name, mode, frame, anchor, map);
    Trajectory estimate = TrajectoryFromArray(trajectory, "trajectory");
    std::optional<Trajectory> gt;
    if (!ground_truth.is_none()) {
        gt = TrajectoryFromArray(ground_truth, "ground_truth");
        if (gt->size() != estimate.size()) {
            throw py::value_error("ground_truth: " + std::to_string(gt->size()) +
                                  " rows, the trajectory has " + std::to_string(estimate.size()));
        }
    }
    const pipeline::PipelineConfig cfg = ConfigFrom(config, solver);
    pipeline::CorrectionRun run;
    {
        py::gil_scoped_release release;
        run = Solve(
            pipeline::PrepareScenario(std::move(sc), std::move(estimate), std::move(gt), cfg), cfg);
    }
    return RunToDict(run);
}

py::dict LoadScenarioDict(const py::object& path) {
    const std::string p = PathOf(path, "path");
    const io::Scenario sc = io::LoadScenario(p);
    const Trajectory estimate = io::LoadTrajectory(sc.estimate);
    std::optional<Trajectory> gt;
    if (sc.ground_truth) gt = io::LoadTrajectory(*sc.ground_truth);
    py::dict d;
    d["name"] = sc.name;
    d["path"] = sc.yaml_path;
    d["mode"] = io::ToString(sc.mode);
    d["frame"] = ToString(sc.frame);
    d["anchor"] = AnchorToDict(sc.anchor);
    d["map"] = MapToList(sc.map);
    d["estimate"] = TrajectoryToArray(estimate);
    d["ground_truth"] = gt ? py::object(TrajectoryToArray(*gt)) : py::object(py::none());
    d["warnings"] = Strings(sc.warnings);
    return d;
}

py::dict Metrics(const py::object& trajectory_en, const py::object& ground_truth_en) {
    const PlanarTrajectory traj = PlanarFromArray(trajectory_en, "trajectory_en");
    const PlanarTrajectory gt = PlanarFromArray(ground_truth_en, "ground_truth_en");
    if (traj.size() != gt.size()) {
        throw py::value_error("ground_truth_en: " + std::to_string(gt.size()) +
                              " rows, trajectory_en has " + std::to_string(traj.size()));
    }
    return MetricsToDict(ComputeMetrics(traj, gt));
}

/// The online corrector on a scenario's map (pipeline::StreamSession, what `driftcorr stream`
/// runs): push() returns each pose's causal estimate at once, finish() the smoothed whole
/// trajectory and the stream's verdict.
class Stream {
public:
    Stream(pipeline::StreamSetup setup, const OnlineConfig& cfg,
           const pipeline::PipelineConfig& pipeline_config)
        : session_(std::make_unique<pipeline::StreamSession>(
              std::move(setup), cfg, pipeline_config.verdict, pipeline_config)) {}

    ~Stream() {
        py::gil_scoped_release release;  // the worker may be finishing a solve
        session_.reset();
    }

    py::dict Push(const py::object& pose) {
        const FramePose in = FramePoseFromArray(pose, "pose");
        pipeline::StreamSession::Output out;
        {
            // Pushes from several threads take turns inside the session (the GIL is released
            // during the solve); synchronous mode solves inside Push, the threaded mode's is O(1).
            py::gil_scoped_release release;
            out = session_->Push(in.t_s, in.p_frame, in.q_frame_body);
        }
        const PushResult& r = out.result;
        if (r.status == PushStatus::kRejectedFinished) {
            throw std::runtime_error("pose: the stream is finished (finish() was called)");
        }
        if (!r.Accepted()) throw py::value_error("pose: " + r.message);
        py::dict d;
        d["index"] = r.index;
        d["pose"] = FramePoseToArray(in.t_s, out.p_frame, out.q_frame_body);
        d["pose_en"] = PlanarPoseToArray(r.corrected);
        d["gap"] = r.gap;
        d["outside_map"] = r.outside_map;
        d["doubt"] = r.doubt;
        d["correction_age_epochs"] = r.correction_age_epochs;
        d["correction_age_s"] = r.correction_age_s;
        d["fresh"] = r.fresh;
        d["covariance"] = r.covariance_ok ? py::object(PoseCovarianceToArray(r.covariance))
                                          : py::object(py::none());
        d["message"] = r.message;
        return d;
    }

    py::dict Finish() {
        std::optional<pipeline::StreamSession::Ending> end;
        std::size_t accepted = 0;
        {
            py::gil_scoped_release release;
            end = session_->Finish();
            accepted = session_->accepted();
        }
        if (!end) throw std::runtime_error("finish() was already called");
        const CorrectionResult& result = end->result;
        const bool usable = Usable(result.status);
        py::dict d;
        d["status"] = driftcorr::ToString(result.status);
        d["message"] = result.message;
        d["usable"] = usable;
        d["poses"] = accepted;
        d["corrected"] =
            end->smoothed ? py::object(TrajectoryToArray(*end->smoothed)) : py::object(py::none());
        d["corrected_en"] =
            usable ? py::object(PlanarToArray(result.corrected)) : py::object(py::none());
        AddCovariance(result, d);
        d["scale_min"] = result.scale_min;
        d["scale_max"] = result.scale_max;
        d["global_scale"] =
            end->scale ? py::object(py::float_(end->scale->scale)) : py::object(py::none());
        d["outputs_before_scale"] = end->outputs_before_scale;
        d["warnings"] = Strings(result.warnings);
        // The stream's verdict (optim/verdict.h JudgeOnline, as `driftcorr stream` prints it).
        d["verdict"] = py::none();
        d["reasons"] = py::list();
        if (end->judged) {
            d["verdict"] = ToString(end->judged->verdict.level);
            d["reasons"] = Strings(end->judged->verdict.reasons);
        }
        return d;
    }

    std::size_t size() {
        py::gil_scoped_release release;
        return session_->size();
    }

private:
    std::unique_ptr<pipeline::StreamSession> session_;
};

std::unique_ptr<Stream> MakeStream(pipeline::StreamSetup setup, const pipeline::PipelineConfig& cfg,
                                   bool synchronous) {
    OnlineConfig online = cfg.online;
    online.corrector = pipeline::CorrectorFor(setup.scenario, cfg);
    online.synchronous = synchronous;
    if (std::string m = online.Validate(); !m.empty()) throw py::value_error("config: " + m);
    return std::make_unique<Stream>(std::move(setup), online, cfg);
}

std::unique_ptr<Stream> StreamFromScenario(const py::object& scenario, const py::object& config,
                                           bool synchronous) {
    const std::string p = PathOf(scenario, "scenario");
    const pipeline::PipelineConfig cfg = ConfigFrom(config, "driftcorr");
    pipeline::StreamSetup setup;
    {
        py::gil_scoped_release release;
        setup = pipeline::LoadStreamSetup(p, cfg);
    }
    return MakeStream(std::move(setup), cfg, synchronous);
}

std::unique_ptr<Stream> StreamFromParts(const py::object& map, const py::object& anchor,
                                        const py::object& frame, const py::object& mode,
                                        const py::object& config, bool synchronous) {
    io::Scenario sc = ScenarioFromParts("", mode, frame, anchor, map);
    const pipeline::PipelineConfig cfg = ConfigFrom(config, "driftcorr");
    pipeline::StreamSetup setup;
    {
        py::gil_scoped_release release;
        setup = pipeline::LoadStreamSetup(std::move(sc), cfg);
    }
    return MakeStream(std::move(setup), cfg, synchronous);
}

}  // namespace
}  // namespace driftcorr::python

PYBIND11_MODULE(_driftcorr, m) {
    namespace py = pybind11;
    using namespace driftcorr::python;
    m.doc() = "driftcorr's C++ library (use the `driftcorr` package, which documents the API)";
    py::register_exception<driftcorr::InputError>(m, "InputError", PyExc_ValueError);

    m.def("load_scenario", &LoadScenarioDict, py::arg("path"));
    m.def("correct_scenario", &CorrectScenario, py::arg("path"), py::arg("config"),
          py::arg("solver"));
    m.def("correct", &CorrectParts, py::arg("trajectory"), py::arg("map"), py::arg("anchor"),
          py::arg("frame"), py::arg("mode"), py::arg("ground_truth"), py::arg("config"),
          py::arg("solver"), py::arg("name"));
    m.def("metrics", &Metrics, py::arg("trajectory_en"), py::arg("ground_truth_en"));

    py::class_<Stream>(m, "Stream")
        .def_static("from_scenario", &StreamFromScenario, py::arg("scenario"), py::arg("config"),
                    py::arg("synchronous"))
        .def_static("from_map", &StreamFromParts, py::arg("map"), py::arg("anchor"),
                    py::arg("frame"), py::arg("mode"), py::arg("config"), py::arg("synchronous"))
        .def("push", &Stream::Push, py::arg("pose"))
        .def("finish", &Stream::Finish)
        .def("__len__", &Stream::size);
}
