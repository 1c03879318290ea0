# Scenario regressions: every paper scenario and the CI variants run through the real `hpa`
# binary with their expect bounds (exit 0 required), plus CLI contract checks.
set(HPA_BIN $<TARGET_FILE:hpa>)
set(SCEN ${CMAKE_CURRENT_SOURCE_DIR})
set(SCEN_OUT ${CMAKE_BINARY_DIR}/scenario_out)

foreach(file
    hover lissajous_T5 lissajous_T4 lissajous_T3_5 lissajous_T5_wind hover_gripper_pull line_impulse
    person_moves_payload person_moves_payload_no_perception
    ci/hover_gripper_pull_nonhybrid ci/line_impulse_nonhybrid ci/lissajous_T5_onboard
    ci/hover_hpa_mpc_truth ci/gripper_pull_truth ci/impulse_top_contact ci/wind_impulse_chaotic
    ci/impulse_draw73 ci/impulse_draw21)
  string(REPLACE "/" "_" name ${file})
  add_test(NAME scenario.${name}
           COMMAND ${HPA_BIN} run ${SCEN}/${file}.yaml --out ${SCEN_OUT}/${name} --quiet)
  set_tests_properties(scenario.${name} PROPERTIES LABELS scenario TIMEOUT 600
                       FIXTURES_SETUP scenario_metrics)
endforeach()

# Change indication: the metrics just written by the scenario tests against scenarios/ci/golden.json
add_test(NAME cli.golden COMMAND ${HPA_BIN} golden --from ${SCEN_OUT} --quiet)
set_tests_properties(cli.golden PROPERTIES LABELS cli FIXTURES_REQUIRED scenario_metrics)
add_test(NAME cli.golden_exact
         COMMAND bash ${SCEN}/tests/golden_exact_test.sh ${HPA_BIN} ${SCEN_OUT}
                 ${SCEN_OUT}/golden_exact)
set_tests_properties(cli.golden_exact PROPERTIES LABELS cli FIXTURES_REQUIRED scenario_metrics)

# Observing a run never changes it: --video, --video-slack-events and --plots give the same metrics
add_test(NAME cli.observation_invariance
         COMMAND bash ${SCEN}/tests/observation_invariance_test.sh ${HPA_BIN} ${SCEN}
                 ${SCEN_OUT}/observation_invariance)
set_tests_properties(cli.observation_invariance PROPERTIES LABELS "cli;scenario" TIMEOUT 600)

# Hostile input: signals to a sweep, shard overflow, list-index spellings, multi-document and
# tagged YAML, messages, killed runs, golden's refusals, FIFOs and devices, unwritable outputs
add_test(NAME cli.hostile_input
         COMMAND bash ${SCEN}/tests/hostile_input_test.sh ${HPA_BIN} ${SCEN}
                 ${SCEN_OUT}/hostile_input)
set_tests_properties(cli.hostile_input PROPERTIES LABELS cli TIMEOUT 600)

# CLI contracts: exit codes, error messages, determinism, render-frame, sweeps
add_test(NAME cli.contract
         COMMAND bash ${SCEN}/tests/cli_contract_test.sh ${HPA_BIN} ${SCEN} ${SCEN_OUT}/cli)
set_tests_properties(cli.contract PROPERTIES LABELS cli TIMEOUT 600)
add_test(NAME cli.sweep
         COMMAND bash ${SCEN}/tests/sweep_cli_test.sh ${HPA_BIN} ${SCEN} ${SCEN_OUT}/sweep)
set_tests_properties(cli.sweep PROPERTIES LABELS cli TIMEOUT 900)

# A real single-node Slurm cluster on localhost runs a sweep as a job array (README's recipe)
add_test(NAME cli.slurm
         COMMAND bash ${SCEN}/tests/slurm_sweep_test.sh ${HPA_BIN} ${SCEN} ${SCEN_OUT}/slurm)
set_tests_properties(cli.slurm PROPERTIES LABELS "cli;slurm" TIMEOUT 600 RUN_SERIAL TRUE)

# Paired sweep comparison: finds a deliberate regression, finds nothing between identical runs
add_test(NAME cli.sweep_diff
         COMMAND bash ${SCEN}/tests/sweep_diff_cli_test.sh ${HPA_BIN} ${SCEN} ${SCEN_OUT}/sweep_diff)
set_tests_properties(cli.sweep_diff PROPERTIES LABELS cli TIMEOUT 600)

# The paper's impulse finding over a Monte Carlo sweep: hpa_mpc crashes less than the baseline
add_test(NAME cli.impulse_finding
         COMMAND bash ${SCEN}/tests/impulse_finding_test.sh ${HPA_BIN} ${SCEN} ${SCEN_OUT}/impulse_finding)
set_tests_properties(cli.impulse_finding PROPERTIES LABELS "cli;scenario" TIMEOUT 900)

add_test(NAME cli.retaut_finding
         COMMAND bash ${SCEN}/tests/retaut_finding_test.sh ${HPA_BIN} ${SCEN} ${SCEN_OUT}/retaut_finding)
set_tests_properties(cli.retaut_finding PROPERTIES LABELS "cli;scenario" TIMEOUT 600)
