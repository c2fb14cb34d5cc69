#include "driftcorr/optim/model_config.h"

namespace driftcorr {

std::optional<ParamProblem> ModelConfig::FindProblem() const {
    if (auto problem = CheckRows(kModelParams, *this)) return problem;
    if (!(scale_range_min <= scale_range_max)) {
        return RelationProblem("scale_range_min", scale_range_min, "<=", "scale_range_max",
                               scale_range_max);
    }
    return std::nullopt;
}

std::string ModelConfig::Validate() const { return ToMessage(kModelParams.section, FindProblem()); }

}  // namespace driftcorr
