/* Stand-in for Simulink Coder's cg_sfun.h (tests only): nothing to declare for the stub. */
