function varargout = load_model(varargin)
%LOAD_MODEL Read a JSON model file.
%   MODEL = hystcomp.load_model(FILE) reads and validates a model file (written by
%   hystcomp.save_model, `hystcomp identify`, or one of models/*.json) into the struct that
%   hystcomp.identify returns.
%
%   Errors: hystcomp:io (missing file, a folder, no permission), hystcomp:invalidModelFile (not
%   JSON, another format version, a field missing or invalid).
%
%   See also hystcomp.save_model, hystcomp.identify.
[varargout{1:max(nargout, 1)}] = hystcomp_mex('load_model', varargin{:});
end
