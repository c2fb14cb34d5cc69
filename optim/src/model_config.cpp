#include "driftcorr/optim/model_config.h"

namespace driftcorr {

std::optional<ParamIssue> ModelConfig::FindIssue() const {
    if (auto issue = CheckRows(kModelParams, *this)) return issue;
    if (!(scale_range_min <= scale_range_max)) {
        return RelationIssue("scale_range_min", scale_range_min, "<=", "scale_range_max",
                             scale_range_max);
    }
    return std::nullopt;
}

std::string ModelConfig::Validate() const { return ToMessage(kModelParams.section, FindIssue()); }

}  // namespace driftcorr
