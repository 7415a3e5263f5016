10 OUTPUT 709;"RST 500"
20 OUTPUT 709;"USE 500"           !Slot 5 Channel 00
30 OUTPUT 709;"STANDBY AUTO LO"
40 OUTPUT 709;"PULSE SS HI HI"
50 OUTPUT 709;"PROFILE FREQ 100 800 200 25E-6"
60 OUTPUT 709;"PSCALE 0.1"
70 OUTPUT 709;"MOVE 20"           !Move auto triggered
80 PAUSE                          !Press CONTINUE to proceed
90 OUTPUT 709;"MOVE -30"          !Move auto triggered
70 OUTPUT 709;"DELAY 5"           !Delay trigger 5 seconds
80 OUTPUT 709;"TRIG HOLD"
90 OUTPUT 709;"MOVE 20 NOWAIT"    !NOWAIT required for TRIG
100 OUTPUT 709;"TRIG"            !Single trigger
110 PAUSE                         !Press CONTINUE to proceed
120 OUTPUT 709;"MOVE -30 NOWAIT" !Single trigger
130 OUTPUT 709;"TRIG"            !Press CONTINUE to proceed
140 PAUSE                         !Reset to trigger auto
150 OUTPUT 709;"TRIG AUTO"
160 OUTPUT 709;"SUSTAIN 10"       !Triggered auto
170 OUTPUT 709;"WAIT 10"          !10 second wait
180 OUTPUT 709;"SUSTAIN 50"
190 OUTPUT 709;"WAIT 10"
200 OUTPUT 709;"SUSTAIN 0"        !Stop to change direction
210 OUTPUT 709;"WAIT 10"
220 OUTPUT 709;"SUSTAIN -10"      !Reverse direction
230 OUTPUT 709;"WAIT 10"
240 OUTPUT 709;"HALT SGL"         !Stop
250 END
