// The definitions of what driftcorr/optim/online_types.h declares.
#include "driftcorr/optim/online_types.h"

namespace driftcorr {

std::optional<ParamProblem> OnlineConfig::FindProblem() const {
    return CheckRows(kOnlineParams, *this);
}

std::string OnlineConfig::Validate() const {
    if (std::string m = corrector.Validate(); !m.empty()) return m;
    return ToMessage(kOnlineParams.section, FindProblem());
}

}  // namespace driftcorr
