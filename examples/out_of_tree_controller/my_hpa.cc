// Your own `hpa`: all of hpa's commands (run, compare, sweep, render-frame, ...) with pd_hover
// registered beside hpa's controllers: my_hpa compare SCENARIO --controllers pd_hover,hpa_mpc
#include "hpa/scenarios/cli.h"
#include "pd_hover.h"

int main(int argc, char** argv) {
  hpa::UsePackageDataDir(HPA_PACKAGE_DATA_DIR);  // the installed data, when it has none of its own
  hpa::RegisterController(PdHoverRegistration());
  return hpa::HpaMain(argc, argv);
}
