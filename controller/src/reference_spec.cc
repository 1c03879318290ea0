#include "hpa/controller/reference_spec.h"

#include "hpa/controller/reference_types.h"

namespace hpa {

double RmseFromS(const ReferenceSpec& spec) { return ReferenceTypeOf(spec).rmse_from_s(spec); }

std::shared_ptr<Reference> MakeReference(const ReferenceSpec& spec, const Params& params) {
  return ReferenceTypeOf(spec).make(spec, params);
}

}  // namespace hpa
