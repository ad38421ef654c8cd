# estlab figure; redraw with: gnuplot p001_dipc_id_error.gp (in this folder)
# data: p001_dipc_id_error.dat
do for [fmt in "png svg"] {
  if (fmt eq "png") {
    set terminal pngcairo enhanced size 900,704
  } else {
    set terminal svg enhanced size 900,704 dynamic
  }
  set output 'p001_dipc_id_error.'.fmt
  reset
  set grid
  set key outside right top noenhanced
  set format x '%h'
  set format y '%h'
  set multiplot layout 2,1 title 'p001_dipc: identified noise vs the truth''s, median and 2.5-97.5 % of runs' noenhanced
  set yrange [10.5:-0.5]
  set lmargin 16
  unset key
  set ytics noenhanced
  set logscale x
  set format x '10^{%L}'
  set xlabel 'relative Frobenius error of Q'
  plot 'p001_dipc_id_error.dat' index 0 using 3:1:4:5:ytic(2) with xerrorbars pt 7 ps 1.2 lc rgb '#d62728'
  set xlabel 'relative Frobenius error of R'
  plot 'p001_dipc_id_error.dat' index 1 using 3:1:4:5:ytic(2) with xerrorbars pt 7 ps 1.2 lc rgb '#d62728'
  unset multiplot
  set output
}
