function varargout = save_model(varargin)
%SAVE_MODEL Write a model to a JSON model file.
%   hystcomp.save_model(MODEL, FILE) writes the model struct MODEL (from hystcomp.identify or
%   hystcomp.load_model, possibly edited) to FILE, atomically: a temporary file in the same
%   folder, then a rename, so that FILE is replaced whole or not at all. The file is the one
%   `hystcomp compensate --model` and every other binding read. MODEL.identification (JSON
%   text) is written as the file's identification; MODEL.report is a read-only view of it and
%   is not written.
%
%   Errors: hystcomp:invalidModel (a field missing or of the wrong class),
%   hystcomp:invalidArgument (a value refused, e.g. a scale <= 0), hystcomp:io (the folder
%   does not exist, no permission).
%
%   See also hystcomp.load_model.
[varargout{1:nargout}] = hystcomp_mex('save_model', varargin{:});
end
