function varargout = identify(varargin)
%IDENTIFY Identify a modified Prandtl-Ishlinskii model from measured samples.
%   MODEL = hystcomp.identify(V, Y) identifies the MPIM of eq. (4) of Gu & Zhu (2014),
%   doi:10.1088/0964-1726/23/9/095029, from drive voltages V (volts) and measured
%   displacements Y (micrometres): vectors of equal length, double, real, finite. It is the
%   library of `hystcomp identify` (constrained least squares by default): the model is
%   strictly increasing along every branch, hence invertible.
%
%   MODEL = hystcomp.identify(V, Y, NAME, VALUE, ...) with the options
%     'n'                 play operators at thresholds (i-1)/n of the input range, eq. (11)
%                         (default 10, at most 1000)
%     'thresholds'        thresholds given explicitly, fractions of the input range in [0, 1),
%                         increasing (instead of 'n')
%     'direction'         'plant' (voltage to displacement, for IHC and WIHC; default) or
%                         'inverse' (displacement to voltage, for DIHC)
%     'method'            'ls' (least squares, the global optimum; default) or 'pso' (the
%                         paper's particle swarm: 'seed', 'particles', 'iterations', 'polish')
%     'warmup'            'auto' (default) or a number of leading samples left out of the fit
%     'holdout'           fraction of the samples at the end held out of the fit and reported
%                         (default 0.2, as the command line and the Python package)
%     'offset'            'fit' (default, for sensors with an arbitrary zero), 'none' or a
%                         value in the displacement's unit
%     'margin'            smallest branch slope kept, normalised (default 0.001)
%     'max_condition'     largest condition number of the regressors (default 1e10)
%     'accept_poor_fit'   true to accept an RMS fit error above 10 % of the output range
%     'voltage_unit', 'displacement_unit'   units written to the model ('V', 'um')
%
%   MODEL is a struct: direction, description, input and output (quantity, unit, offset,
%   scale: physical = offset + scale * normalised), input_range, thresholds, weights, a1, a2
%   (normalised, eq. (4)), identification (the fit report as JSON text, what save_model
%   writes) and report (the same, decoded: samples, fit.rms_percent, holdout, ...).
%
%   Errors: hystcomp:wrongType, hystcomp:wrongSize, hystcomp:empty, hystcomp:nonFiniteInput,
%   hystcomp:lengthMismatch, hystcomp:invalidOption, hystcomp:invalidArgument (too few or
%   constant samples, an option out of range), hystcomp:identificationFailed (no model fits:
%   wrong column or sign, poor fit; the message says what to change).
%
%   See also hystcomp.save_model, hystcomp.Compensator, hystcomp.predict.
[varargout{1:max(nargout, 1)}] = hystcomp_mex('identify', varargin{:});
end
