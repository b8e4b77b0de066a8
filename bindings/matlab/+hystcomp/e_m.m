function varargout = e_m(varargin)
%E_M Maximum tracking error, (D1) of Gu & Zhu (2014), in percent of the desired range.
%   E = hystcomp.e_m(YD, Y) is max|Y - YD| / (max YD - min YD) * 100 (ERRATA item 2), for the
%   desired trajectory YD and the measured response Y (vectors of equal length, finite, YD not
%   constant).
%
%   See also hystcomp.e_rms, hystcomp.e_mhe.
[varargout{1:max(nargout, 1)}] = hystcomp_mex('e_m', varargin{:});
end
