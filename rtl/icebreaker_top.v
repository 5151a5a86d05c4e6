// icebreaker_top: omniloc on the iCEBreaker (iCE40UP5K-SG48) board.
//
// Clock: the board's 12 MHz oscillator drives the design directly (CLK_HZ = OMNILOC_BOARD_CLOCK_HZ;
// rates and clocks come from common/regmap.json "link"). Why not the PLL: 40 MHz cannot be made
// exactly from 12 MHz (the nearest PLL output is 39.75 MHz), so neither the 100 Hz window nor 1 Mbaud
// would divide exactly; at 12 MHz both do (120000 cycles a window, 12 cycles a bit), the encoder
// inputs are still sampled at 30x the fastest edge rate of the paper's motors, and no PLL lock has to
// be waited for. The bitstream is still timed against OMNILOC_PAPER_CLOCK_HZ (40 MHz, the paper's
// myRIO clock), so the same RTL is shown to close at that frequency.
// Pins (constraints/icebreaker.pcf): encoders on PMOD1A (A0..A3 on the top row, B0..B3 on the
// bottom row), FT2232H channel B UART (FPGA receives on 6, transmits on 9), the user button as
// reset, the green LED for link activity and the red LED for errors (both active low; a gyro
// fault or a missing gyro is an error), the ICM-42688-P gyro's SPI on PMOD1B (docs/GYRO.md
// "Wiring": pin 1 CS, 2 MOSI, 3 MISO, 4 SCLK, the Digilent SPI PMOD order).
// CHANNELS 3: a three-wheel robot's board, channel 3's pins (A3, B3) unused.
// Reset: held for 16 cycles after configuration and while the button is pressed (synchronised).
`resetall
`timescale 1ns / 1ps
`default_nettype none
`include "omniloc_regs.vh"

module icebreaker_top #(
    parameter integer CHANNELS = `OMNILOC_CHANNELS   // wheels: 4, or 3 (`make bitstream CHANNELS=3`)
) (
    input  wire       CLK,
    input  wire       BTN_N,
    input  wire [`OMNILOC_CHANNELS-1:0] ENC_A,
    input  wire [`OMNILOC_CHANNELS-1:0] ENC_B,
    input  wire       RX,
    output wire       TX,
    output wire       GYRO_CS_N,
    output wire       GYRO_MOSI,
    input  wire       GYRO_MISO,
    output wire       GYRO_SCLK,
    output wire       LEDG_N,
    output wire       LEDR_N
);

// Power-on and button reset, synchronous to CLK.
reg [1:0] btn_sync_q = 2'b00;
reg [4:0] por_q = 5'd0;
always @(posedge CLK) begin
    btn_sync_q <= {btn_sync_q[0], BTN_N};
    if (!btn_sync_q[1]) por_q <= 5'd0;
    else if (!por_q[4]) por_q <= por_q + 5'd1;
end
wire rst = !por_q[4];

wire activity, error;
omniloc_top #(.CLK_HZ(`OMNILOC_BOARD_CLOCK_HZ), .TICK_HZ(`OMNILOC_TICK_HZ), .BAUD(`OMNILOC_UART_BAUD),
              .CHANNELS(CHANNELS)) u_omniloc (
    .clk_i(CLK), .rst_i(rst), .enc_a_i(ENC_A), .enc_b_i(ENC_B),
    .uart_rx_i(RX), .uart_tx_o(TX),
    .spi_sclk_o(GYRO_SCLK), .spi_mosi_o(GYRO_MOSI), .spi_miso_i(GYRO_MISO), .spi_cs_n_o(GYRO_CS_N),
    .activity_o(activity), .error_o(error));

assign LEDG_N = !activity;
assign LEDR_N = !error;

endmodule

`default_nettype wire
