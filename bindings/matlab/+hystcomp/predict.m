function varargout = predict(varargin)
%PREDICT Run a model forward over a signal.
%   Y = hystcomp.predict(MODEL, X) runs the model (eq. (4), in its physical units; then its
%   creep and vibration links, when it has them) over the input X from rest (zero operator
%   memory, eq. (1)): for a plant model, drive voltage in and displacement out, so that hystcomp.predict(MODEL, hystcomp.compensate(MODEL, 'ihc', YD))
%   returns YD (P[C[y_d]] = y_d). Y has the shape of X.
%
%   See also hystcomp.compensate, hystcomp.identify.
[varargout{1:max(nargout, 1)}] = hystcomp_mex('predict', varargin{:});
end
