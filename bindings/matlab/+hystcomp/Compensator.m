classdef Compensator < handle
%COMPENSATOR A feedforward hysteresis compensator: desired position in, drive voltage out.
%   C = hystcomp.Compensator(MODEL, METHOD) builds the compensator METHOD of MODEL (a model
%   struct from hystcomp.identify or hystcomp.load_model, or a model file's name), in the
%   model's physical units: desired position in (e.g. um), drive voltage out (e.g. V).
%   METHOD: 'ihc' (the inverse of eqs. (5)-(8), solved exactly), 'ihc-delayed', 'wihc'
%   (eq. (9), exactly), 'wihc-delayed' (the one-sample-delayed loops of real-time
%   implementations), 'ihc-guarded', 'wihc-guarded' (the delayed loops under-relaxed so
%   that they cannot oscillate on any invertible model; plant models) or 'dihc' (eq. (10);
%   inverse models).
%   C = hystcomp.Compensator(MODEL, METHOD, [VMIN VMAX]) sets the drive limits (the model's
%   voltage unit; default, or []: the range the model was identified on). Invertibility over
%   the limits is checked here (hystcomp:notInvertible).
%   A plain delayed method whose loop gain over the limits is 1 or more can ring between the
%   limits after a jump, and is refused (hystcomp:unstableDelay, the gain in the message):
%   use the exact or guarded method, identify the model for delayed compensation, or
%   C = hystcomp.Compensator(MODEL, METHOD, LIMITS, 'AllowUnstableDelay', true) to build it
%   anyway (the drive still never leaves the limits).
%
%   Every output lies within the limits and is never NaN. The compensator keeps its state
%   (the operators' memory) from call to call, like a block in a control loop:
%     V = C.step(YD)       one sample
%     V = C.process(YD)    a whole vector, sample after sample (V has the shape of YD)
%     C.reset()            back to the initial state (zero memory, eq. (1))
%     D = C.diagnostics()  since the last reset: saturated (out of reach, clamped),
%                          loop_saturated (a delayed loop clamped a reachable position),
%                          non_finite, limits, delayed_loop_gain (the worst-case gain of
%                          the method family's one-sample-delayed loop; NaN for dihc: at or
%                          above 1 the plain delayed loop can ring after a jump),
%                          preview (samples the drive lags the desired position, for a model
%                          with a vibration link; 0 otherwise)
%     delete(C)            frees it (also when the last reference goes); a deleted
%                          compensator refuses every call with hystcomp:invalidHandle
%
%   NaN or infinite desired positions are refused (hystcomp:nonFiniteInput) and leave the
%   state unchanged.
%
%   See also hystcomp.compensate, hystcomp.identify.

    properties (SetAccess = private)
        % The method, e.g. 'ihc'.
        method = '';
        % The drive limits [v_min v_max], in the model's voltage unit.
        limits = [];
    end

    properties (Access = private, Transient)
        % The gateway's id of the compensator (0: none). Transient: an id means nothing in
        % another session, so a saved compensator loads without one.
        id = uint64(0);
    end

    methods
        function obj = Compensator(model, method, limits, varargin)
            if nargin < 2
                error('hystcomp:nargin', ...
                      'hystcomp.Compensator(model, method, [v_min v_max], ''AllowUnstableDelay'', false)');
            end
            if nargin < 3
                limits = [];
            end
            allow = false;
            if mod(numel(varargin), 2) ~= 0
                error('hystcomp:nargin', ...
                      'options come as name, value pairs: ''AllowUnstableDelay'', true');
            end
            for k = 1:2:numel(varargin)
                if ~(ischar(varargin{k}) && strcmpi(varargin{k}, 'AllowUnstableDelay'))
                    error('hystcomp:unknownOption', ...
                          'unknown option (the one option is ''AllowUnstableDelay'')');
                end
                allow = varargin{k + 1};
            end
            obj.id = hystcomp_mex('compensator_new', model, method, limits, allow);
            obj.method = lower(method);
            d = hystcomp_mex('compensator_diagnostics', obj.id);
            obj.limits = d.limits;
        end

        function varargout = step(obj, varargin)
            %STEP The drive voltage for one desired position (the state advances).
            [varargout{1:max(nargout, 1)}] = hystcomp_mex('compensator_step', obj.id, varargin{:});
        end

        function varargout = process(obj, varargin)
            %PROCESS The drive voltage for a vector of desired positions, in order.
            [varargout{1:max(nargout, 1)}] = hystcomp_mex('compensator_process', obj.id, varargin{:});
        end

        function varargout = reset(obj, varargin)
            %RESET Back to the initial state (zero operator memory, eq. (1)).
            [varargout{1:nargout}] = hystcomp_mex('compensator_reset', obj.id, varargin{:});
        end

        function varargout = diagnostics(obj, varargin)
            %DIAGNOSTICS Counts since the last reset, the limits and the delayed loop gain.
            [varargout{1:max(nargout, 1)}] = hystcomp_mex('compensator_diagnostics', obj.id, varargin{:});
        end

        function delete(obj)
            %DELETE Frees the compensator; later calls raise hystcomp:invalidHandle.
            hystcomp_mex('compensator_free', obj.id);
            obj.id = uint64(0);
        end
    end
end
