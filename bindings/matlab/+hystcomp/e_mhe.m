function varargout = e_mhe(varargin)
%E_MHE Maximum hysteresis error, eq. (12) of Gu & Zhu (2014), in percent of the desired range.
%   E = hystcomp.e_mhe(YD, Y) is the largest vertical width of the Y versus YD map (ERRATA item
%   6): the range of YD is cut into 100 equal bins, and the widest max Y - min Y within one bin
%   is divided by max YD - min YD.
%
%   E = hystcomp.e_mhe(YD, Y, BINS) uses BINS bins: at least 1 and at most
%   max(1, floor(numel(YD) / 10)) (with fewer than 10 samples per bin on average, bins hold one
%   sample or none and e_mhe reads low).
%
%   See also hystcomp.e_m, hystcomp.e_rms.
[varargout{1:max(nargout, 1)}] = hystcomp_mex('e_mhe', varargin{:});
end
