# Expected run time (seconds, CPU of one core, measured with `ctest -j2` on a 2-core machine) of
# the longest tests. ctest -j starts higher-COST tests first; a fresh clone has no timing data
# of its own, so without these the longest tests may start last and leave one core idle at the
# end of the suite. Only the order depends on these numbers, never a verdict.
set(_hpa_test_costs
  cli.impulse_wide_finding 160   cli.bounds_held_out 60    cli.observation_invariance 75
  cli.retaut_pushes_finding 50   cli.flight_stack 45       cli.perception_finding 40
  cli.flight_boundary 40         scenario.ci_team3_lift_cameras 30   cli.replay 25
  cli.readme_your_controller 25  cli.install 20            cli.sweep_diff 20
  cli.hostile_input 18           cli.sweep 15              cli.flight_stack_rate_loop 15
  cli.impulse_finding 15         cli.team_video 15         cli.team_flight_stack 12)
while(_hpa_test_costs)
  list(POP_FRONT _hpa_test_costs _name _cost_s)
  if(TEST ${_name})
    set_tests_properties(${_name} PROPERTIES COST ${_cost_s})
  endif()
endwhile()
