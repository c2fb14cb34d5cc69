// The definitions of what driftcorr/pipeline/online.h declares.
#include "driftcorr/pipeline/online.h"

#include <cmath>
#include <stdexcept>
#include <tuple>
#include <utility>

#include "driftcorr/core/errors.h"
#include "driftcorr/core/format.h"

namespace driftcorr::pipeline {

StreamSetup LoadStreamSetup(const std::string& scenario_path, const PipelineConfig& config) {
    return LoadStreamSetup(io::LoadScenario(scenario_path), config);
}

StreamSetup LoadStreamSetup(io::Scenario scenario, const PipelineConfig& config) {
    StreamSetup setup;
    setup.scenario = std::move(scenario);
    const io::Scenario& sc = setup.scenario;
    if (!sc.anchor.yaw_deg || sc.anchor.position_search_m > 0.0) {
        throw InputError(sc.yaml_path, 0,
                         sc.anchor.yaw_deg ? "anchor.position_search_m" : "anchor.yaw_deg",
                         "a start estimated from the map (yaw_deg: auto, position_search_m) needs "
                         "the whole trajectory: use correct, or give the start for stream");
    }
    setup.scale_auto = sc.anchor.scale_auto;
    setup.scale = sc.anchor.scale_auto ? 1.0 : sc.anchor.scale;
    std::unique_ptr<WorldFrame> world;
    try {
        world = std::make_unique<WorldFrame>(sc.anchor);
    } catch (const InputError& e) {
        throw InputError(sc.yaml_path, 0, e.key(), e.what());
    }
    setup.anchor = world->planar_anchor();
    // The route is not known in advance: the field covers the whole map (for roads, the region
    // is unbounded and RasteriseRoads clips it to the network's extent).
    const Eigen::AlignedBox2d everywhere(Eigen::Vector2d(-1e7, -1e7), Eigen::Vector2d(1e7, 1e7));
    setup.field = LoadMapField(sc, *world, config, everywhere, sc.anchor.z_m, setup.network);
    return setup;
}

PlanarPose ToPlanarPose(double t_s, const Eigen::Vector3d& p_frame,
                        const Eigen::Quaterniond& q_frame_body, const StreamSetup& setup,
                        std::optional<double> scale) {
    Trajectory one;
    one.t_s = {t_s};
    one.p_frame = {scale.value_or(setup.scale) * p_frame};
    one.q_frame_body = {q_frame_body};
    const PlanarTrajectory planar = ToPlanar(one, setup.scenario.frame, setup.anchor);
    PlanarPose out;
    out.t_s = t_s;
    out.p_en = planar.p_en[0];
    out.up_m = planar.up_m[0];
    out.yaw_rad = planar.yaw_rad[0];
    return out;
}

std::pair<Eigen::Vector3d, Eigen::Quaterniond> FromPlanarPose(
    const PlanarPose& corrected, const PlanarPose& reference, const Eigen::Vector3d& p_frame,
    const Eigen::Quaterniond& q_frame_body, FrameAxes axes, const PlanarAnchor& anchor) {
    auto planar = [](const PlanarPose& p) {
        PlanarTrajectory t;
        t.t_s = {p.t_s};
        t.p_en = {p.p_en};
        t.up_m = {p.up_m};
        if (p.yaw_rad) t.yaw_rad = {*p.yaw_rad};
        return t;
    };
    Trajectory original;
    original.t_s = {reference.t_s};
    original.p_frame = {p_frame};
    original.q_frame_body = {q_frame_body};
    const Trajectory out = FromPlanar(planar(corrected), planar(reference), original, axes, anchor);
    return {out.p_frame[0], out.q_frame_body[0]};
}

StreamSession::StreamSession(StreamSetup setup, const OnlineConfig& config,
                             const VerdictConfig& verdict, const PipelineConfig& pipeline)
    : setup_(std::make_unique<StreamSetup>(std::move(setup))),
      pipeline_(pipeline),
      config_(config),
      verdict_(verdict) {
    if (!setup_->scale_auto) corrector_ = std::make_unique<OnlineCorrector>(&setup_->field, config);
}

StreamSession::~StreamSession() = default;

namespace {

PushResult Rejected(PushStatus status, std::string message) {
    PushResult r;
    r.status = status;
    r.message = std::move(message);
    return r;
}

void Append(PlanarTrajectory& t, const PlanarPose& p) {
    t.t_s.push_back(p.t_s);
    t.p_en.push_back(p.p_en);
    t.up_m.push_back(p.up_m);
    if (p.yaw_rad) t.yaw_rad.push_back(*p.yaw_rad);
}

}  // namespace

// Changes nothing when the search throws. `fit`: FitGlobalScale on the poses so far, when the
// caller has made it.
void StreamSession::StartAtScale(std::optional<ScaleFitResult> fit) {
    const TrialField on_setup_field =
        [this](const PlanarTrajectory&,
               std::optional<TraversableField>&) -> const TraversableField& {
        return setup_->field;
    };
    if (!fit)
        fit = FitGlobalScale(setup_->scenario, pipeline_, unit_, setup_->anchor, setup_->field);
    found_ = ChooseGlobalScale(setup_->scenario, pipeline_, unit_, setup_->anchor, std::move(*fit),
                               on_setup_field);
    setup_->scale = found_->scale;
    before_scale_ = accepted_.size();
    corrector_ = std::make_unique<OnlineCorrector>(&setup_->field, config_);
    reference_ = PlanarTrajectory{};
    for (std::size_t i = 0; i < accepted_.size(); ++i) {
        const PlanarPose input = ToPlanarPose(accepted_.t_s[i], accepted_.p_frame[i],
                                              accepted_.q_frame_body[i], *setup_);
        corrector_->Push(input);
        Append(reference_, input);
    }
    unit_ = PlanarTrajectory{};
}

StreamSession::Output StreamSession::PushSearchingScale(double t_s, const Eigen::Vector3d& p_frame,
                                                        const Eigen::Quaterniond& q_frame_body) {
    Output out;
    const PlanarPose unit = ToPlanarPose(t_s, p_frame, q_frame_body, *setup_, 1.0);
    const bool finite =
        std::isfinite(t_s) && p_frame.allFinite() && q_frame_body.coeffs().allFinite();
    if (!finite) {
        out.result = Rejected(PushStatus::kRejectedNonFinite, "pose has a NaN or inf value");
        return out;
    }
    if (!accepted_.t_s.empty() && !(t_s > accepted_.t_s.back())) {
        out.result =
            Rejected(PushStatus::kRejectedTime, "timestamp " + FormatFixed(t_s, 6) +
                                                    " is not after the previous one (" +
                                                    FormatFixed(accepted_.t_s.back(), 6) + ")");
        return out;
    }
    if (!unit_.p_en.empty()) unit_path_ += (unit.p_en - unit_.p_en.back()).norm();
    Append(unit_, unit);
    accepted_.t_s.push_back(t_s);
    accepted_.p_frame.push_back(p_frame);
    accepted_.q_frame_body.push_back(q_frame_body);
    // The best scale so far, refitted each time the path has grown by a quarter; the search
    // ends once that scale's leading path is as long as the batch's.
    if (unit_path_ > 0.0 && unit_path_ >= next_fit_path_) {
        std::optional<ScaleFitResult> fit;
        try {
            fit = FitGlobalScale(setup_->scenario, pipeline_, unit_, setup_->anchor, setup_->field);
            provisional_scale_ = fit->candidates.front().scale;
            fitted_ = true;
        } catch (const InputError&) {
            // every step a stop so far, or nothing fits yet: the next fit decides
        }
        next_fit_path_ = 1.25 * unit_path_;
        if (fit && provisional_scale_ * unit_path_ >= ScaleLeadPathM()) {
            try {
                StartAtScale(std::move(fit));
            } catch (const InputError&) {
                // not found on these poses: the search goes on (Finish tries once more)
            }
        }
    }
    out.input = ToPlanarPose(t_s, p_frame, q_frame_body, *setup_, provisional_scale_);
    out.result.index = accepted_.size() - 1;
    out.result.corrected = out.input;
    out.result.doubt = kDoubtScaleSearch;
    out.result.covariance_ok = false;
    std::tie(out.p_frame, out.q_frame_body) =
        FromPlanarPose(out.result.corrected, out.input, p_frame, q_frame_body,
                       setup_->scenario.frame, setup_->anchor);
    // The output as written; Finish leaves it out of the causal check.
    causal_.t_s.push_back(out.result.corrected.t_s);
    causal_.p_en.push_back(out.result.corrected.p_en);
    causal_.up_m.push_back(out.result.corrected.up_m);
    return out;
}

StreamSession::Output StreamSession::Push(double t_s, const Eigen::Vector3d& p_frame,
                                          const Eigen::Quaterniond& q_frame_body) {
    const std::lock_guard<std::mutex> lock(mutex_);
    if (!corrector_) {
        if (finished_) {
            Output out;
            out.result = Rejected(PushStatus::kRejectedFinished, "Push after Finish()");
            return out;
        }
        return PushSearchingScale(t_s, p_frame, q_frame_body);
    }
    Output out;
    out.input = ToPlanarPose(t_s, p_frame, q_frame_body, *setup_);
    out.result = corrector_->Push(out.input);
    if (!out.result.Accepted()) return out;
    std::tie(out.p_frame, out.q_frame_body) =
        FromPlanarPose(out.result.corrected, out.input, p_frame, q_frame_body,
                       setup_->scenario.frame, setup_->anchor);
    accepted_.t_s.push_back(t_s);
    accepted_.p_frame.push_back(p_frame);
    accepted_.q_frame_body.push_back(q_frame_body);
    reference_.t_s.push_back(out.input.t_s);
    reference_.p_en.push_back(out.input.p_en);
    reference_.up_m.push_back(out.input.up_m);
    reference_.yaw_rad.push_back(*out.input.yaw_rad);
    causal_.t_s.push_back(out.result.corrected.t_s);
    causal_.p_en.push_back(out.result.corrected.p_en);
    causal_.up_m.push_back(out.result.corrected.up_m);
    return out;
}

std::optional<StreamSession::Ending> StreamSession::Finish() {
    const std::lock_guard<std::mutex> lock(mutex_);
    if (finished_) return std::nullopt;
    finished_ = true;
    Ending end;
    if (!corrector_) {
        // `scale: auto` and a stream too short to have found the scale: found on what it has.
        try {
            if (accepted_.size() < 3) {
                throw InputError(setup_->scenario.yaml_path, 0, "anchor.scale",
                                 "`scale: auto` needs at least 3 poses");
            }
            StartAtScale();
        } catch (const InputError& e) {
            end.result.status = SolveStatus::kFailed;
            end.result.message = e.what();
            return end;
        }
    }
    end.scale = found_;
    end.outputs_before_scale = before_scale_;
    end.result = corrector_->Finish();
    if (!Usable(end.result.status)) return end;
    // Outputs before the scale was found are the input at a scale being searched, not the
    // corrector's: the causal check leaves them out (they count as the smoothed poses).
    PlanarTrajectory causal = causal_;
    for (std::size_t i = 0; i < before_scale_ && i < causal.size(); ++i) {
        causal.p_en[i] = end.result.corrected.p_en[i];
        causal.up_m[i] = end.result.corrected.up_m[i];
    }
    end.judged = JudgeOnline(reference_, causal, &setup_->field, config_.corrector.model,
                             end.result, verdict_);
    end.smoothed = FromPlanar(end.result.corrected, reference_, accepted_, setup_->scenario.frame,
                              setup_->anchor);
    return end;
}

OnlineStatistics StreamSession::Statistics() const {
    const std::lock_guard<std::mutex> lock(mutex_);
    if (!corrector_) {
        OnlineStatistics st;
        st.poses = accepted_.size();
        return st;
    }
    return corrector_->Statistics();
}

std::size_t StreamSession::size() const {
    const std::lock_guard<std::mutex> lock(mutex_);
    return corrector_ ? corrector_->size() : 0;
}

std::size_t StreamSession::accepted() const {
    const std::lock_guard<std::mutex> lock(mutex_);
    return accepted_.size();
}

}  // namespace driftcorr::pipeline
