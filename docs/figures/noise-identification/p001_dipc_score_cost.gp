# estlab figure; redraw with: gnuplot p001_dipc_score_cost.gp (in this folder)
# data: p001_dipc_score_cost.dat
do for [fmt in "png svg"] {
  if (fmt eq "png") {
    set terminal pngcairo enhanced size 1000,600
  } else {
    set terminal svg enhanced size 1000,600 dynamic
  }
  set output 'p001_dipc_score_cost.'.fmt
  reset
  set grid
  set key outside right top noenhanced
  set format x '%h'
  set format y '%h'
  set title 'p001_dipc: score (1 = the truth''s noise) vs cost per run' noenhanced
  set logscale x
  set format x '10^{%L}'
  set xlabel 'mean wall time per run, identification + filter [s]'
  set logscale y
  set ylabel 'score [95 % CI] (log scale)'
  plot 'p001_dipc_score_cost.dat' index 0 using 1:2:3:4 with yerrorbars pt 7 ps 1.2 lc rgb '#1f77b4' title 'ekf' noenhanced, \
       '' index 0 using 1:2:5 with labels left offset 1,0 font ',9' tc rgb '#1f77b4' noenhanced notitle, \
       'p001_dipc_score_cost.dat' index 1 using 1:2:3:4 with yerrorbars pt 7 ps 1.2 lc rgb '#d62728' title 'ukf3' noenhanced, \
       '' index 1 using 1:2:5 with labels left offset 1,0 font ',9' tc rgb '#d62728' noenhanced notitle
  set output
}
