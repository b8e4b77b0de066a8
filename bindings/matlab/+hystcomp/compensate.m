function varargout = compensate(varargin)
%COMPENSATE Drive voltage for a whole desired trajectory, in one call.
%   V = hystcomp.compensate(MODEL, METHOD, YD) returns the drive voltage V for the desired
%   positions YD (a vector, the model's displacement unit), from the initial state (zero
%   operator memory, eq. (1)), as hystcomp.Compensator(MODEL, METHOD).process(YD) would.
%   METHOD: 'ihc' (eqs. (5)-(8)), 'ihc-delayed', 'wihc' (eq. (9)), 'wihc-delayed',
%   'ihc-guarded', 'wihc-guarded' (plant models) or 'dihc' (eq. (10), inverse models). MODEL is
%   a model struct or a model file's name. A plain delayed method whose loop can oscillate is
%   refused (hystcomp:unstableDelay); hystcomp.Compensator takes the explicit override.
%   V has the shape of YD, lies within the drive limits and is never NaN. For a model with a
%   vibration link, V(k) is the drive for YD(k) (the inverse's preview removed).
%
%   V = hystcomp.compensate(MODEL, METHOD, YD, [VMIN VMAX]) sets the drive limits (the model's
%   voltage unit; default: the range the model was identified on).
%
%   [V, D] = hystcomp.compensate(...) also returns the diagnostics: saturated (desired
%   positions out of reach, clamped), loop_saturated (a delayed loop clamped a reachable
%   position), non_finite (0: NaN is refused) and the limits used.
%
%   Errors: hystcomp:notInvertible (the model bends back within the limits),
%   hystcomp:wrongDirection (IHC and WIHC need a plant model, DIHC an inverse one),
%   hystcomp:unstableDelay (a plain delayed loop with loop gain >= 1),
%   hystcomp:invalidArgument (unknown method, limits), and those of the arguments.
%
%   See also hystcomp.Compensator, hystcomp.predict.
[varargout{1:max(nargout, 1)}] = hystcomp_mex('compensate', varargin{:});
end
